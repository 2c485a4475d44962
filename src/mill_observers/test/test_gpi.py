"""GpiObserver: discrete pole placement, exact-model convergence, tracking, parameters."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.signal
from mill_common.parameters import ParameterError
from mill_common.signals import Estimate
from mill_observers.base import Observer
from mill_observers.gpi import GpiObserver, GpiParams
from numpy.polynomial import Polynomial

# x axis of Beltrán 2013 Table 1: a = p/2π, m_e = m + J/a², b = 1/(a·m_e) ≈ 20.96
_A = 0.003175 / (2.0 * math.pi)
B = 1.0 / (_A * (17.551 + 19.623e-6 / _A**2))


def _continuous_model(b: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Beltrán 2013 eq. (14), built independently of the observer."""
    a = np.diag(np.ones(6), k=1)
    bb = np.zeros((7, 1))
    bb[1, 0] = b
    c = np.zeros((1, 7))
    c[0, 0] = 1.0
    return a, bb, c


def _clusters(values: np.ndarray, centres: np.ndarray) -> dict[int, list[complex]]:
    groups: dict[int, list[complex]] = {}
    for v in values:
        groups.setdefault(int(np.argmin(np.abs(centres - v))), []).append(complex(v))
    return groups


@pytest.mark.parametrize('T', [1e-3, 1e-4])
def test_discrete_model_is_the_exact_zoh_sampling_of_eq14(T: float) -> None:
    obs = GpiObserver(B, T)
    a, bb, c = _continuous_model(B)
    ad_ref, bd_ref, *_ = scipy.signal.cont2discrete((a, bb, c, np.zeros((1, 1))), T, 'zoh')
    ad, bd, cc = obs.discrete_model()
    np.testing.assert_allclose(ad, ad_ref, rtol=1e-12, atol=0.0)
    np.testing.assert_allclose(bd, bd_ref[:, 0], rtol=1e-12, atol=1e-300)
    np.testing.assert_array_equal(cc, c[0])


@pytest.mark.parametrize('T', [1e-3, 1e-4])
def test_error_poles_are_eq18_roots_mapped_by_exp_st(T: float) -> None:
    obs = GpiObserver(B, T)
    s = obs.continuous_poles()
    # Beltrán 2013 eq. (18) with the paper's values, rebuilt here from its factors.
    p18 = Polynomial([700.0, 1.0]) * Polynomial([700.0**2, 2 * 0.7071 * 700.0, 1.0]) ** 3
    # Compare polynomials, not roots: numerical roots of a triple factor are inexact.
    np.testing.assert_allclose(Polynomial.fromroots(s).coef.real, p18.coef, rtol=1e-12)
    z = np.exp(s * T)
    np.testing.assert_allclose(obs.discrete_poles(), z, rtol=1e-13)

    ad, _, c = obs.discrete_model()
    _, l_gain = obs.gains()
    err = ad - np.outer(l_gain, c)
    # The characteristic polynomial is well conditioned even with the triple roots.
    want = np.poly(z).real
    assert np.max(np.abs(np.poly(err).real - want)) < 1e-9
    # eig() resolves a triple root only to ~ε^(1/3) ≈ 6e-6, so individual eigenvalues
    # are checked loosely and each triple's mean (a symmetric function) tightly.
    got = obs.error_poles()
    groups = _clusters(got, np.unique(np.round(z, 12)))
    centres = np.unique(np.round(z, 12))
    assert sorted(len(g) for g in groups.values()) == [1, 3, 3]
    for i, members in groups.items():
        assert np.max(np.abs(np.array(members) - centres[i])) < 1e-4
        assert abs(np.mean(members) - centres[i]) < 1e-9
    # The current-estimator error matrix (I − M C)·Ad has the same poles.
    m_gain, _ = obs.gains()
    np.testing.assert_allclose(l_gain, ad @ m_gain, rtol=1e-12)
    err_cur = (np.eye(7) - np.outer(m_gain, c)) @ ad
    assert np.max(np.abs(np.poly(err_cur).real - want)) < 1e-9


def test_continuous_coefficients_of_eq17() -> None:
    beta = GpiObserver(B, 1e-3).continuous_coefficients()
    w, zeta, p = 700.0, 0.7071, 700.0
    assert beta.shape == (7,)
    assert beta[0] == pytest.approx(p + 6 * zeta * w, rel=1e-12)  # β6 = Σ roots
    assert beta[-1] == pytest.approx(p * w**6, rel=1e-12)  # β0 ≈ 8.2e19
    assert beta[-1] > 8e19


def _run_polynomial(T: float, u_of_k, xi: Polynomial, x0: float, v0: float, seconds: float):
    """Observer on the exactly sampled ẍ = b·u + ξ(t), ξ a polynomial, u held per sample."""
    obs = GpiObserver(B, T)
    xi_i2 = xi.integ(2, lbnd=0.0)  # ∬ξ from rest at t = 0
    xi_i1 = xi.integ(1, lbnd=0.0)
    xu = vu = 0.0  # input part of the motion, exact for a held u
    rows = []
    for k in range(round(seconds / T)):
        t = k * T
        x = x0 + v0 * t + xi_i2(t) + xu
        v = v0 + xi_i1(t) + vu
        est = obs.correct(x)
        u = u_of_k(k)
        obs.predict(u)
        rows.append((t, est.disturbance, xi(t), est.velocity, v))
        xu += vu * T + 0.5 * B * u * T * T
        vu += B * u * T
    return np.array(rows)


# ξ of eq. (13), degree 4 [m/s²], and a random held input.
_XI4 = Polynomial([2.0, 30.0, -400.0, 3000.0, -9000.0])
_LATE = 0.05  # [s]
# The initial errors reach ξ⁽⁴⁾ = 2e5 m/s⁶; by 50 ms the slowest pair has decayed by
# e^(−495·0.05) ≈ 2e-11 (times the triple-root t² growth), measured ≈ 1e-8 of the
# disturbance scale at 1 kHz and 10 kHz. 1e-7 keeps a 10× margin over that, rounding
# (≈ 1e-12) is far below, and an unmodelled t⁵ term already breaks it (test below).
_XI_TOL = 1e-7


def _late_errors(T: float, xi: Polynomial) -> tuple[float, float, np.ndarray]:
    rng = np.random.default_rng(1)
    us = rng.uniform(-0.2, 0.2, size=round(0.12 / T))
    rows = _run_polynomial(T, lambda k: float(us[k]), xi, 0.05, 0.003, 0.12)
    late = rows[rows[:, 0] >= _LATE]
    scale = float(np.max(np.abs(rows[:, 2])))
    xi_err = float(np.max(np.abs(late[:, 1] - late[:, 2]))) / scale
    v_err = float(np.max(np.abs(late[:, 3] - late[:, 4])))
    return xi_err, v_err, rows


@pytest.mark.parametrize('T', [1e-3, 1e-4])
def test_polynomial_disturbance_of_degree_4_is_estimated_exactly(T: float) -> None:
    # The model (14) is exact for this ξ, so the error obeys e(k+1) = (Ad − L C)·e.
    xi_err, v_err, rows = _late_errors(T, _XI4)
    assert xi_err < _XI_TOL
    assert v_err < 1e-9  # [m/s]; measured ≈ 2e-11
    # Not trivially converged: at the start the error was the full disturbance.
    assert abs(rows[0, 1] - rows[0, 2]) == pytest.approx(2.0)


def test_polynomial_of_degree_5_is_not_exact() -> None:
    # A 5th-degree term violates the Taylor model of eq. (13): a steady error
    # ≈ ξ⁽⁵⁾·7e-14 s⁵ remains, which shows the test above is sensitive to the model.
    xi_err, _, _ = _late_errors(1e-3, _XI4 + Polynomial([0, 0, 0, 0, 0, 1e6]))
    assert xi_err > _XI_TOL


@pytest.mark.parametrize('T', [1e-3, 1e-4])
def test_sinusoidal_disturbance_is_tracked_with_small_lag(T: float) -> None:
    # ξ = A sin(ωt) at 10 Hz, well inside the 700 rad/s bandwidth: the estimation error
    # ~ (ω/ω_o)^5 relative is ~1e-5, so 1e-3·A after the transient is a safe bound.
    amp, w = 3.0, 2.0 * math.pi * 10.0
    obs = GpiObserver(B, T)
    rows = []
    for k in range(round(0.3 / T)):
        t = k * T
        x = amp * t / w - amp * math.sin(w * t) / w**2  # exact: ẍ = A sin(ωt) from rest
        v = amp / w - amp * math.cos(w * t) / w
        est = obs.correct(x)
        obs.predict(0.0)
        rows.append((t, est.disturbance, amp * math.sin(w * t), est.velocity, v))
    rows_a = np.array(rows)
    late = rows_a[rows_a[:, 0] >= 0.05]
    assert np.max(np.abs(late[:, 1] - late[:, 2])) < 1e-3 * amp
    # Velocity error ≈ ξ error / ω: 1e-4 of the velocity amplitude A/ω is ample.
    assert np.max(np.abs(late[:, 3] - late[:, 4])) < 1e-4 * amp / w
    # Lag: shift the estimate back in time; the best fit must be within one sample.
    shifts = range(0, 6)
    errs = [np.max(np.abs(late[s:, 1] - late[: len(late) - s, 2])) for s in shifts]
    assert int(np.argmin(errs)) == 0


def test_first_correct_initialises_from_measurement() -> None:
    obs = GpiObserver(B, 1e-3)
    assert isinstance(obs, Observer)
    assert not obs.initialised
    est = obs.correct(0.042)
    assert est == Estimate(0.042, 0.0, 0.0)
    np.testing.assert_array_equal(obs.state, [0.042, 0, 0, 0, 0, 0, 0])
    obs.predict(0.0)
    again = obs.correct(0.042)
    assert again == Estimate(0.042, 0.0, 0.0)  # at rest and consistent: nothing moves
    obs.reset()
    assert obs.correct(-0.01).position == -0.01


def test_bad_calls_do_not_corrupt_state() -> None:
    obs = GpiObserver(B, 1e-3)
    with pytest.raises(RuntimeError):
        obs.predict(0.0)
    obs.correct(0.01)
    before = obs.state
    with pytest.raises(ValueError, match='not finite'):
        obs.predict(math.nan)
    with pytest.raises(ValueError, match='not finite'):
        obs.correct(math.inf)
    np.testing.assert_array_equal(obs.state, before)


@pytest.mark.parametrize('name', ['omega_o', 'zeta_o', 'pole_o'])
@pytest.mark.parametrize('value', [0.0, -1.0, math.nan, math.inf])
def test_non_positive_parameters_are_refused(name: str, value: float) -> None:
    with pytest.raises(ParameterError) as info:
        GpiObserver.from_parameters(B, 1e-3, {name: value})
    assert info.value.name == f'gpi.{name}'
    with pytest.raises(ParameterError, match=f'gpi.{name}'):
        GpiObserver(B, 1e-3, GpiParams(**{name: value}))


@pytest.mark.parametrize('b', [0.0, math.nan, math.inf])
def test_bad_input_gain_is_refused(b: float) -> None:
    with pytest.raises(ParameterError, match='input_gain'):
        GpiObserver(b, 1e-3)


@pytest.mark.parametrize('T', [0.0, -1e-3, math.nan])
def test_bad_sample_period_is_refused(T: float) -> None:
    with pytest.raises(ParameterError, match='sample_period'):
        GpiObserver(B, T)


def test_parameters_defaults_are_the_papers_values() -> None:
    defaults = {p.name: p.default for p in GpiObserver.PARAMETERS}
    assert defaults == {
        'omega_o': 700.0,
        'zeta_o': 0.7071,
        'pole_o': 700.0,
        'discretisation': 'current',
    }
    assert GpiObserver.PREFIX == 'gpi'
    obs = GpiObserver.from_parameters(B, 1e-3, {'omega_o': 500})  # YAML int accepted
    assert np.min(np.abs(obs.continuous_poles())) == pytest.approx(500.0)
    assert all(p.description for p in GpiObserver.PARAMETERS)


def test_negative_input_gain_is_handled() -> None:
    # b < 0 only flips the input direction; the error dynamics do not depend on b.
    T = 1e-3
    obs = GpiObserver(-B, T)
    x = v = 0.0
    for _ in range(100):
        est = obs.correct(x)
        obs.predict(0.01)
        x += v * T + 0.5 * (-B) * 0.01 * T * T
        v += (-B) * 0.01 * T
    assert est.disturbance == pytest.approx(0.0, abs=1e-6)


def test_the_sampling_series_is_the_matrix_exponential() -> None:
    import numpy as np
    import pytest
    import scipy.linalg
    from mill_observers.chain_design import _exp_nilpotent

    n = 7
    shift = np.eye(n, k=1)
    augmented = np.zeros((n + 1, n + 1))
    augmented[:n, :n] = shift
    augmented[1, n] = 1.0
    for m in (augmented, -shift, 0.3 * shift):
        assert np.max(np.abs(_exp_nilpotent(m) - scipy.linalg.expm(m))) < 1e-15
    with pytest.raises(ValueError, match='not nilpotent'):
        _exp_nilpotent(np.eye(3, k=1) + np.eye(3, k=-1))
