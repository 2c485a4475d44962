"""Force process of Rubio 2013 eq. (1)-(3): gains, exact affine-input integration, depth steps."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mill_common.parameters import ParameterError
from mill_models.force_process import (
    DEFAULT_DEPTH_PROFILE,
    ForceProcessModel,
    ForceProcessParams,
    ForceProcessPlant,
)
from scipy.integrate import solve_ivp


def test_paper_constants_and_derived_values() -> None:
    m = ForceProcessModel()
    assert m.sample_period == pytest.approx(60.0 / 715.0, rel=1e-15)
    assert m.tau_m == 0.1
    # τ_c = 1/(N_t S_s): the tooth-passing period at 715 rpm, 4 flutes
    assert m.tau_c == pytest.approx(60.0 / (4 * 715.0), rel=1e-15)
    # K_p = K_c a r / (N_t S_s) = 1200·2·4/(4·715/60) N·s/mm at 2 mm
    assert m.process_gain(2.0) == pytest.approx(1200.0 * 2.0 * 4.0 / (4.0 * 715.0 / 60.0))
    assert m.steady_feed(1200.0, 2.0) == pytest.approx(1200.0 / m.process_gain(2.0))


def test_default_depth_profile_has_steps_up_and_down() -> None:
    depths = [d for _, d in DEFAULT_DEPTH_PROFILE]
    steps = np.diff(depths)
    assert np.any(steps > 0) and np.any(steps < 0)
    m = ForceProcessModel()
    assert m.depth_at(0.0) == 2.0
    assert m.depth_at(1.999) == 2.0
    assert m.depth_at(2.0) == 3.0  # right-continuous
    assert m.depth_at(-1.0) == 2.0
    assert m.depth_changes(1.0, 4.5) == [2.0, 4.0]


@pytest.mark.parametrize(
    'profile',
    [
        [1.0, 2.0],  # does not start at 0
        [0.0, 2.0, 1.0],  # odd length
        [0.0, 2.0, 0.0, 3.0],  # times not increasing
        [0.0, -1.0],  # negative depth
        [0.0, math.nan],
    ],
)
def test_bad_depth_profiles_are_refused(profile: list[float]) -> None:
    with pytest.raises(ParameterError, match='depth_profile'):
        ForceProcessModel(ForceProcessParams(depth_profile=profile))


def test_from_parameters_takes_the_flat_profile() -> None:
    m = ForceProcessModel.from_parameters({'depth_profile': [0.0, 1.0, 0.5, 2.5]})
    assert m.depth_profile == ((0.0, 1.0), (0.5, 2.5))
    with pytest.raises(ParameterError, match=r'force_process\.flutes'):
        ForceProcessModel.from_parameters({'flutes': 0})


def _ode_force(m: ForceProcessModel, x0, u0: float, slope: float, h: float, depth: float):
    a, b, _ = m.state_space()

    def rhs(t, x):
        return a @ x + b * (u0 + slope * t)

    sol = solve_ivp(rhs, (0.0, h), x0, rtol=1e-12, atol=1e-12, method='DOP853')
    return m.process_gain(depth) * sol.y[1, -1], sol.y[:, -1]


@pytest.mark.parametrize(('u0', 'slope'), [(5.0, 0.0), (3.0, 40.0), (8.0, -60.0)])
def test_step_integrates_an_affine_feed_exactly(u0: float, slope: float) -> None:
    m = ForceProcessModel(ForceProcessParams(depth_profile=[0.0, 2.5]))
    plant = ForceProcessPlant(m)
    plant.reset(4.0)
    x0 = plant.state
    force = plant.step(u0, slope, m.sample_period)
    ref_force, ref_x = _ode_force(m, x0, u0, slope, m.sample_period, 2.5)
    assert force == pytest.approx(ref_force, rel=1e-9)
    np.testing.assert_allclose(plant.state, ref_x, rtol=1e-9)
    assert plant.time == pytest.approx(m.sample_period)


def test_constant_feed_settles_at_gain_times_feed() -> None:
    m = ForceProcessModel(ForceProcessParams(depth_profile=[0.0, 3.0]))
    plant = ForceProcessPlant(m)
    for _ in range(200):
        plant.step(4.0, 0.0, m.sample_period)
    assert plant.force == pytest.approx(m.process_gain(3.0) * 4.0, rel=1e-9)
    assert plant.feed_actual == pytest.approx(4.0, rel=1e-9)


def test_depth_step_jumps_the_force_and_splits_the_trace() -> None:
    m = ForceProcessModel(ForceProcessParams(depth_profile=[0.0, 2.0, 0.05, 4.0]))
    plant = ForceProcessPlant(m)
    plant.reset(5.0)
    before = plant.force
    pieces = plant.trace(5.0, 0.0, 0.1, 0.01)
    assert len(pieces) == 2
    (t1, f1), (t2, f2) = pieces
    assert t1[-1] == pytest.approx(0.05) and t2[0] == pytest.approx(0.05)
    assert f1[-1] == pytest.approx(before)  # steady state, old depth up to the step
    assert f2[0] == pytest.approx(2.0 * before)  # the depth doubles: the force jumps
    for t, _ in pieces:
        assert (len(t) - 1) % 2 == 0  # even number of intervals (Simpson)
        assert np.max(np.diff(t)) <= 0.01 + 1e-12
    assert plant.force == pytest.approx(2.0 * before)


def test_trace_and_step_agree() -> None:
    m = ForceProcessModel()
    a, b = ForceProcessPlant(m), ForceProcessPlant(m)
    t_start = 1.95  # the 2 mm → 3 mm step at 2 s falls inside
    a.reset(3.0, t_start)
    b.reset(3.0, t_start)
    fa = a.step(6.0, 25.0, m.sample_period)
    pieces = b.trace(6.0, 25.0, m.sample_period, m.sample_period / 10)
    assert pieces[-1][1][-1] == pytest.approx(fa, rel=1e-12)
    np.testing.assert_allclose(a.state, b.state, rtol=1e-12)


def test_non_finite_feed_is_refused_and_state_kept() -> None:
    plant = ForceProcessPlant()
    plant.reset(2.0)
    x = plant.state
    with pytest.raises(ValueError, match='finite'):
        plant.step(math.nan, 0.0, 0.01)
    with pytest.raises(ValueError, match='finite'):
        plant.step(1.0, math.inf, 0.01)
    np.testing.assert_array_equal(plant.state, x)
