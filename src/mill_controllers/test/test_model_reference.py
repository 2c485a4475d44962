"""R, S, T design of Rubio 2013 eq. (7)-(11): Diophantine identity, model following, causality."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.signal
from mill_common.parameters import ParameterError
from mill_controllers.model_reference import (
    ForceControlDesigner,
    ForceControlParams,
    ModelReferenceForceController,
    RstController,
    RstDesignParams,
)
from mill_models.force_process import ForceProcessModel
from mill_models.reference_model import reference_model

MODEL = ForceProcessModel()
T = MODEL.sample_period
BETAS = [-1.0, -0.5, -0.3, 0.0, 0.5, 1.0]


def _roots_match(p: np.ndarray, q: np.ndarray, tol: float = 1e-6) -> None:
    a = np.sort_complex(np.roots(p))
    b = np.sort_complex(np.roots(q))
    assert len(a) == len(b)
    for z in a:
        assert np.min(np.abs(b - z)) < tol


def test_reference_model_parameters_are_the_papers() -> None:
    d = ForceControlDesigner(MODEL)
    assert d.damping == 0.7
    # ω_n = 2.5/T_r, T_r = three spindle periods
    assert d.omega_n == pytest.approx(2.5 / (3.0 * 60.0 / 715.0))
    num, den = reference_model(0.7, d.omega_n)
    assert np.polyval(num, 0.0) / np.polyval(den, 0.0) == 1.0


@pytest.mark.parametrize('beta', BETAS)
def test_closed_loop_polynomial_is_model_times_observer_times_cancelled_zeros(beta: float) -> None:
    des = ForceControlDesigner(MODEL).design(beta)
    a, b = des.plant.den, des.plant.num
    # Rubio 2013 eq. (10): A R + B S = B⁺ A_m A_o, every factor built here independently
    char = np.polyadd(np.polymul(a, des.r), np.polymul(b, des.s))
    bplus = np.real(np.poly(np.roots(np.trim_zeros(b, 'f'))))  # all zeros are stable
    am = des.reference.den
    wanted = np.polymul(bplus, np.polymul(am, np.poly([ForceControlDesigner(MODEL).observer_pole])))
    np.testing.assert_allclose(char, wanted, rtol=0, atol=1e-13)
    np.testing.assert_allclose(des.characteristic_polynomial(), char, atol=1e-15)
    # and in the reduced form A R₁ + B⁻ S = A_m A_o
    red = np.polyadd(np.polymul(a, des.r1), np.polymul(des.b_minus, des.s))
    expected = np.polymul(des.model_poles, des.observer)
    np.testing.assert_allclose(np.trim_zeros(red, 'f'), expected, atol=1e-13)
    # the model poles are those of the β-discretised eq. (7)
    _roots_match(des.model_poles, des.reference.den)
    # closed-loop poles = reference-model poles ∪ observer ∪ cancelled plant zeros
    expected_roots = np.concatenate(
        [np.roots(des.reference.den), np.roots(des.observer), np.roots(des.b_plus)]
    )
    _roots_match(char, np.real(np.poly(expected_roots)))
    assert des.r[0] == 1.0  # R monic
    assert len(des.s) == len(des.t) == len(des.r)  # deg S, deg T <= deg R: causal


def test_every_zero_is_stable_so_every_zero_is_cancelled() -> None:
    for beta in np.linspace(-1.0, 1.0, 21):
        des = ForceControlDesigner(MODEL).design(float(beta))
        assert len(des.b_minus) == 1  # only the gain remains in B⁻


@pytest.mark.parametrize('beta', [-1.0, 0.5, 1.0])
def test_unstable_zeros_are_kept_when_not_cancelled(beta: float) -> None:
    """A small cancel radius puts zeros in B⁻: the identity and unit DC gain still hold."""
    d = ForceControlDesigner(MODEL, RstDesignParams(zero_cancel_radius=0.2, observer_degree=2))
    des = d.design(beta)
    assert len(des.b_minus) >= 2
    np.testing.assert_allclose(
        des.characteristic_polynomial(), des.designed_polynomial(), atol=1e-13
    )
    # closed loop B T / (A R + B S) has unit DC gain
    cl_num = np.polymul(des.plant.num, des.t)
    assert np.polyval(cl_num, 1.0) / np.polyval(des.characteristic_polynomial(), 1.0) == (
        pytest.approx(1.0, rel=1e-12)
    )


@pytest.mark.parametrize('tau_o', [0.0, 0.05])
@pytest.mark.parametrize('n_o', [0, 1, 3])
def test_observer_polynomial_choices(tau_o: float, n_o: int) -> None:
    d = ForceControlDesigner(
        MODEL, RstDesignParams(observer_degree=n_o, observer_time_constant=tau_o)
    )
    pole = math.exp(-T / (tau_o or MODEL.tau_c))
    np.testing.assert_allclose(np.roots(d.observer) if n_o else [], [pole] * n_o, atol=1e-4)
    for beta in (-0.3, 0.0, 0.7):
        des = d.design(beta)
        np.testing.assert_allclose(
            des.characteristic_polynomial(), des.designed_polynomial(), atol=1e-13
        )


def _closed_loop(ctrl, beta: float, gain: float, n: int, r: np.ndarray) -> tuple[np.ndarray, ...]:
    """Discrete loop: plant K·H_β(z), controller ctrl; y_k uses u_j, j < k."""
    h = ForceControlDesigner(MODEL).design(beta).plant
    num, den = gain * h.num, h.den
    zi = np.zeros(len(den) - 1)
    y = np.zeros(n)
    u = np.zeros(n)
    for k in range(n):
        y[k] = zi[0]  # strictly proper: output from the state only
        u[k] = ctrl.update(r[k], y[k])
        _, zi = scipy.signal.lfilter(num, den, [u[k]], zi=zi)
    return y, u


@pytest.mark.parametrize('beta', BETAS)
def test_closed_loop_follows_the_discrete_reference_model_exactly(beta: float) -> None:
    ctrl = ModelReferenceForceController(MODEL, ForceControlParams(beta=beta))
    ctrl.set_depth(3.0)
    n = 40
    r = np.full(n, 1200.0)
    r[20:] = 900.0
    y, u = _closed_loop(ctrl, beta, MODEL.process_gain(3.0), n, r)
    des = ctrl.design
    ym = scipy.signal.lfilter(des.reference.num, des.reference.den, r)
    np.testing.assert_allclose(y, ym, rtol=0, atol=1e-9)
    assert u[19] == pytest.approx(MODEL.steady_feed(1200.0, 3.0), rel=1e-4)


def test_controller_is_causal() -> None:
    """Outputs up to k0 do not depend on inputs after k0 (and do depend on earlier ones)."""
    rng = np.random.default_rng(7)
    n, k0 = 30, 14
    r1 = rng.uniform(800, 1500, n)
    y1 = rng.uniform(600, 1800, n)
    r2, y2 = r1.copy(), y1.copy()
    r2[k0 + 1 :] += 300.0
    y2[k0 + 1 :] -= 250.0
    for beta in (-0.3, 0.0, 1.0):
        outs = []
        for r, y in ((r1, y1), (r2, y2)):
            c = ModelReferenceForceController(MODEL, ForceControlParams(beta=beta))
            outs.append(np.array([c.update(rk, yk) for rk, yk in zip(r, y, strict=True)]))
        np.testing.assert_array_equal(outs[0][: k0 + 1], outs[1][: k0 + 1])
        assert np.all(outs[0][k0 + 1 :] != outs[1][k0 + 1 :])


def test_depth_scales_s_and_t_only() -> None:
    """u = (T r − S y)/K_p − (R − 1)u: doubling K_p halves the first output."""
    a = ModelReferenceForceController(MODEL, ForceControlParams(beta=-0.3))
    b = ModelReferenceForceController(MODEL, ForceControlParams(beta=-0.3))
    a.set_depth(1.0)
    b.set_depth(2.0)
    assert a.update(1200.0, 100.0) == pytest.approx(2.0 * b.update(1200.0, 100.0), rel=1e-12)


def test_record_applied_changes_the_memory() -> None:
    a = ModelReferenceForceController(MODEL, ForceControlParams(beta=0.5))
    b = ModelReferenceForceController(MODEL, ForceControlParams(beta=0.5))
    for c in (a, b):
        c.update(1200.0, 0.0)
    b.record_applied(1.0)
    assert a.update(1200.0, 50.0) != b.update(1200.0, 50.0)


def test_non_finite_input_is_refused_without_touching_the_memory() -> None:
    a = ModelReferenceForceController(MODEL)
    b = ModelReferenceForceController(MODEL)
    a.update(1200.0, 10.0)
    b.update(1200.0, 10.0)
    with pytest.raises(ValueError, match='non-finite'):
        a.update(1200.0, math.nan)
    with pytest.raises(ValueError, match='non-finite'):
        a.update(math.inf, 5.0)
    assert a.update(1200.0, 20.0) == b.update(1200.0, 20.0)


def test_bad_parameters_are_refused() -> None:
    with pytest.raises(ParameterError, match='beta'):
        ModelReferenceForceController(MODEL, ForceControlParams(beta=1.2))
    with pytest.raises(ParameterError, match='damping_ratio'):
        ModelReferenceForceController.from_parameters(MODEL, {'damping_ratio': -1.0})
    with pytest.raises(ParameterError, match='observer_degree'):
        ModelReferenceForceController(MODEL, ForceControlParams(observer_degree=-1))
    with pytest.raises(ValueError, match='gain'):
        RstController(ForceControlDesigner(MODEL).design(0.0), gain=0.0)
