"""GpiObserver's three discretisations: predictor, current, continuous (eq. (15) integrated)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.integrate
from mill_common.parameters import ParameterError
from mill_observers.delay import DelayCompensation
from mill_observers.gpi import DISCRETISATIONS, GpiObserver, GpiParams

B = 20.96  # x axis of Beltrán 2013 Table 1 [(m/s²)/(N·m)]
T = 1e-3


def _eq15_over_a_period(beta: np.ndarray, x: np.ndarray, u: float, ys: np.ndarray):
    """Eq. (15) in raw units, integrated numerically over one period with u held and y the
    polynomial through the samples ys (the last two bound the period):
    ẋ = A x + e₁ b u + β (y − x₀), A the chain of eq. (14)."""
    gain = beta  # [β6, β5, …, β0] multiply the innovation of x₀ … x₆
    times = T * np.arange(1 - len(ys), 1)
    path = np.polynomial.Polynomial.fit(times, ys, len(ys) - 1)

    def rhs(t: float, state: np.ndarray) -> np.ndarray:
        y = path(t - T)
        d = np.append(state[1:], 0.0) + gain * (y - state[0])
        d[1] += B * u
        return d

    # Component j is about 1e-3·T^−j in size (m, m/s, … m/s⁶): an absolute tolerance each.
    atol = 1e-16 * T ** -np.arange(7.0)
    sol = scipy.integrate.solve_ivp(rhs, (0.0, T), x, method='DOP853', rtol=1e-12, atol=atol)
    return sol.y[:, -1]


def test_continuous_is_eq15_integrated_with_the_held_command_and_a_parabolic_position() -> None:
    obs = GpiObserver(B, T, GpiParams(discretisation='continuous'))
    beta = obs.continuous_coefficients()
    rng = np.random.default_rng(3)
    ys = 1e-3 * np.cumsum(rng.normal(size=6))
    us = rng.uniform(-0.5, 0.5, size=6)
    obs.correct(float(ys[0]))
    x = obs.state
    for k in range(1, 6):
        obs.predict(float(us[k - 1]))
        obs.correct(float(ys[k]))
        # a line through the first two samples, then the parabola through the last three
        x = _eq15_over_a_period(beta, x, float(us[k - 1]), ys[max(k - 2, 0) : k + 1])
        # the integrator's tolerance, 1e-12 relative per component, times a few steps
        np.testing.assert_allclose(obs.state, x, rtol=1e-9, atol=0.0)


def test_predictor_gives_the_current_estimators_estimate_before_the_measurement() -> None:
    current = GpiObserver(B, T)
    predictor = GpiObserver(B, T, GpiParams(discretisation='predictor'))
    rng = np.random.default_rng(4)
    current.correct(0.01)
    predictor.correct(0.01)
    for k in range(50):
        u = float(rng.uniform(-0.5, 0.5))
        current.predict(u)
        predictor.predict(u)
        before = current.state  # x̄(k|k−1) in raw units
        y = 0.01 + 1e-4 * math.sin(0.3 * k)
        est = predictor.correct(y)
        assert (est.position, est.velocity, est.disturbance) == pytest.approx(
            tuple(before[:3]), rel=1e-12, abs=1e-15
        )
        current.correct(y)
        np.testing.assert_array_equal(predictor.state, current.state)  # the same recursion


@pytest.mark.parametrize('discretisation', DISCRETISATIONS)
def test_every_discretisation_learns_a_constant_disturbance(discretisation: str) -> None:
    # ẍ = b u + ξ with ξ = 2 m/s² and u = 0: the model is exact (and the parabola of
    # `continuous`), the estimate converges at the designed rate (slowest pole pair
    # −495 s⁻¹, triple): 1e-6 by 0.1 s is ample. With a straight line between samples
    # `continuous` stays 2.8 % low.
    obs = GpiObserver(B, T, GpiParams(discretisation=discretisation))
    for k in range(101):
        t = k * T
        est = obs.correct(0.5 * 2.0 * t * t)
        obs.predict(0.0)
    assert est.disturbance == pytest.approx(2.0, rel=1e-6)
    assert est.velocity == pytest.approx(2.0 * 0.1, rel=1e-6)


def test_continuous_coasts_and_stretches_a_period_at_rest_without_moving() -> None:
    obs = GpiObserver(B, T, GpiParams(discretisation='continuous'))
    obs.correct(0.02)
    obs.predict(0.0)
    obs.predict(0.0)  # a lost measurement: the model's own position starts the next period
    obs.elapse(0.0, 0.3)  # a tick late
    est = obs.correct(0.02)
    # nothing but rounding: a few ε·0.02 m in the scaled state z_j = T^j·x_j
    assert est.position == pytest.approx(0.02, abs=1e-16)
    assert est.velocity == pytest.approx(0.0, abs=1e-16 / T)
    assert est.disturbance == pytest.approx(0.0, abs=1e-16 / T**2)
    assert obs.predicted([0.0, 0.0]).position == pytest.approx(0.02, abs=1e-16)


@pytest.mark.parametrize('value', ['exact', '', 1])
def test_an_unknown_discretisation_is_refused(value: object) -> None:
    with pytest.raises(ParameterError) as info:
        GpiObserver.from_parameters(B, T, {'discretisation': value})
    assert info.value.name == 'gpi.discretisation'
    assert ('current, predictor, continuous' in str(info.value)) == isinstance(value, str)


def test_with_a_command_delay_predictor_gives_the_same_as_current() -> None:
    # The delay compensation runs the model ahead from the state after predict(), which
    # both share (docs/papers.md says so).
    loops = [
        DelayCompensation(GpiObserver(B, T, GpiParams(discretisation=d)), 1, T)
        for d in ('current', 'predictor')
    ]
    for k in range(30):
        y = 0.01 + 1e-4 * math.sin(0.3 * k)
        ests = [loop.correct(y) for loop in loops]
        assert ests[0] == ests[1]
        for loop in loops:
            loop.command(0.1 * math.cos(0.2 * k))
