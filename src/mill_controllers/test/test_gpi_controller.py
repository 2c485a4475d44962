"""GPI controller of Chávez-Conde eq. (9)-(12): closed-loop roots, tracking, interface."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
import scipy.linalg
from mill_common.parameters import ParameterError
from mill_common.signals import AxisReference, ControlInputs, Estimate
from mill_controllers.base import AxisController
from mill_controllers.gpi_controller import GpiController, GpiParams
from mill_trajectory.bezier import BezierRestToRest

# Chávez-Conde section 5, x axis; c_t read as translational (as the suite's plant does).
M, J, C_B, C_T, MU = 5.0, 0.005, 2.5, 2.5, 0.3
A = 0.01 / (2.0 * math.pi)
ETA1 = M + J / A**2  # 1978.9 kg
ETA2 = C_B + C_T
B = 1.0 / (A * ETA1)  # 0.3175 (m/s²)/(N·m)
KAPPA = ETA2 / ETA1
T = 1e-3
EST = Estimate(0.0, 0.0, 0.0)
ZERO = AxisReference(0.0, 0.0, 0.0)


def plant_zoh(kappa: float = KAPPA, period: float = T) -> tuple[np.ndarray, np.ndarray]:
    """Exact ZOH sampling of [x, ẋ]' = [[0, 1], [0, −κ]]·[x, ẋ] + [0, 1]·a_in."""
    aug = np.zeros((3, 3))
    aug[0, 1] = 1.0
    aug[1, 1] = -kappa
    aug[1, 2] = 1.0
    phi = scipy.linalg.expm(aug * period)
    return phi[:2, :2], phi[:2, 2]


def controller_realisation(ctrl: AxisController, order: int = 1, n: int = 12):
    """(A_c, B_c, C_c, D_c) of the y → τ map (ref = 0) by Ho-Kalman from its impulse response.

    Black box: only compute() is called. The first call fixes F(0) = 0. The map is first
    order: the ∫e integrator is cancelled by a zero (the GPI law is, input-output, the lead
    compensator τ = −(1/b)·((k1 − (k2 − κ)κ) s + k0)/(s + k2 − κ)·y), so the Hankel matrix
    has rank 1, which the assert checks.
    """
    ctrl.compute(ControlInputs(0.0, 0.0, ZERO, EST))
    h = [ctrl.compute(ControlInputs(T, 1.0, ZERO, EST))]
    h += [ctrl.compute(ControlInputs((k + 1) * T, 0.0, ZERO, EST)) for k in range(1, 2 * n + 2)]
    hankel = np.array([[h[i + j + 1] for j in range(n)] for i in range(n)])
    shifted = np.array([[h[i + j + 2] for j in range(n)] for i in range(n)])
    u, s, vt = np.linalg.svd(hankel)
    assert s[order] < 1e-9 * s[0], f'controller order > {order}: singular values {s[:4]}'
    sq = np.sqrt(s[:order])
    obs = u[:, :order] * sq
    con = (vt[:order].T * sq).T
    a_c = np.linalg.pinv(obs) @ shifted @ np.linalg.pinv(con)
    return a_c, con[:, 0], obs[0], h[0]


def closed_loop_poles(ctrl: AxisController, kappa: float = KAPPA) -> np.ndarray:
    """Continuous-equivalent roots log(z)/T of the sampled plant + controller loop."""
    a_p, g_p = plant_zoh(kappa)
    b_p = B * g_p  # torque input
    a_c, b_c, c_c, d_c = controller_realisation(ctrl)
    top = np.hstack([a_p + d_c * np.outer(b_p, [1.0, 0.0]), np.outer(b_p, c_c)])
    bottom = np.hstack([np.outer(b_c, [1.0, 0.0]), a_c])
    z = np.linalg.eigvals(np.vstack([top, bottom]))
    return np.log(z.astype(complex)) / T


def _match(got: np.ndarray, want: list[complex], atol: float) -> None:
    """Pair each wanted root with the nearest got root."""
    rest = list(got)
    for w in want:
        i = int(np.argmin([abs(g - w) for g in rest]))
        assert abs(rest[i] - w) < atol, f'no root near {w}: {got}'
        rest.pop(i)


@pytest.mark.parametrize(
    ('omega_n', 'zeta', 'pole'), [(80.0, 0.9, 80.0), (40.0, 0.5, 120.0), (150.0, 1.2, 30.0)]
)
def test_sampled_closed_loop_roots_are_the_designed_ones(
    omega_n: float, zeta: float, pole: float
) -> None:
    ctrl = GpiController(
        B,
        T,
        GpiParams(omega_n=omega_n, zeta=zeta, pole=pole, damping_rate=KAPPA, torque_limit=math.inf),
    )
    got = closed_loop_poles(ctrl)
    wd = complex(zeta**2 - 1.0) ** 0.5 * omega_n
    want = [-zeta * omega_n + wd, -zeta * omega_n - wd, complex(-pole)]
    assert len(got) == 3
    _match(got, want, atol=1e-6 * omega_n)


def test_gains_tend_to_the_continuous_alphas() -> None:
    ctrl = GpiController(B, T, GpiParams(damping_rate=KAPPA))
    # (s² + 144 s + 6400)(s + 80)
    assert ctrl.alphas == pytest.approx((512000.0, 17920.0, 224.0))
    assert ctrl.gains == pytest.approx((458025, 16497.4, 208.705), rel=1e-4)
    fine = GpiController(B, 1e-6, GpiParams(damping_rate=KAPPA))
    assert fine.gains == pytest.approx(fine.alphas, rel=1e-3)


def test_continuous_runs_the_printed_alphas_and_zoh_is_the_default() -> None:
    cont = GpiController(B, T, GpiParams(damping_rate=KAPPA, discretisation='continuous'))
    assert cont.gains == cont.alphas == (512000.0, 17920.0, 224.0)
    assert GpiController(B, T, GpiParams(damping_rate=KAPPA)).gains != cont.alphas
    with pytest.raises(ParameterError, match=r'gpi\.discretisation'):
        GpiController(B, T, GpiParams(discretisation='tustin'))


def simulate(ctrl, force: float = 0.0, coulomb: float = 0.0, t_end: float = 3.5):
    """Chávez-Conde eq. (1) x axis, exactly sampled, Coulomb sign taken at the sample start."""
    a_p, g_p = plant_zoh()
    path = BezierRestToRest()
    x = np.zeros(2)
    errors, torques = [], []
    for k in range(round(t_end / T) + 1):
        t = k * T
        ref = path.sample(t).axis(0)
        tau = ctrl.compute(ControlInputs(t, float(x[0]), ref, EST))
        errors.append(x[0] - ref.position)
        torques.append(tau)
        # η1 ẍ + η2 ẋ + μ sign(ẋ) = τ/a − F_c
        x = a_p @ x + g_p * (B * tau - (coulomb * np.sign(x[1]) + force) / ETA1)
    return np.array(errors), np.array(torques)


def test_bezier_move_is_tracked_on_the_nominal_plant() -> None:
    ctrl = GpiController(B, T, GpiParams(damping_rate=KAPPA))
    e, tau = simulate(ctrl)
    # Only the zero-order hold of the feed-forward F̈* is not exact: measured 2.8e-10 m.
    assert np.max(np.abs(e)) < 1e-9
    assert np.max(np.abs(tau)) == pytest.approx(0.058, rel=0.05)  # η1 a max|F̈*|


def test_coulomb_friction_leaves_the_predicted_small_error() -> None:
    ctrl = GpiController(B, T, GpiParams(damping_rate=KAPPA))
    e, _ = simulate(ctrl, coulomb=MU)
    k0, _, k2 = ctrl.gains
    # Constant ξ = −μ while ẋ > 0: steady e = (k2 − κ) ξ / (η1 k0) = −6.9e-8 m.
    predicted = (k2 - KAPPA) * (-MU) / (ETA1 * k0)
    mid = e[round(1.0 / T) : round(2.0 / T)]
    assert np.mean(mid) == pytest.approx(predicted, rel=0.02)
    assert np.max(np.abs(e)) < 1.1 * abs(predicted)


def test_est_is_ignored_and_repeated_calls_are_idempotent() -> None:
    ctrl = GpiController(B, T)
    ref = AxisReference(0.001, 0.002, 0.0)
    ctrl.compute(ControlInputs(0.0, 0.0, ref, EST))
    other = copy.deepcopy(ctrl)
    u1 = ctrl.compute(ControlInputs(T, 1e-4, ref, EST))
    u2 = other.compute(ControlInputs(T, 1e-4, ref, Estimate(5.0, -3.0, 1e3)))
    assert u1 == u2
    assert ctrl.compute(ControlInputs(T, 1e-4, ref, EST)) == u1  # same t: nothing integrated twice
    with pytest.raises(ValueError, match='backwards'):
        ctrl.compute(ControlInputs(0.0, 1e-4, ref, EST))
    with pytest.raises(ValueError, match='non-finite'):
        ctrl.compute(ControlInputs(2 * T, math.nan, ref, EST))


def test_torque_is_clipped_and_the_clipped_torque_is_reconstructed() -> None:
    ctrl = GpiController(B, T, GpiParams(torque_limit=0.01))
    big = AxisReference(0.01, 0.0, 0.0)
    assert ctrl.compute(ControlInputs(0.0, 0.0, big, EST)) == pytest.approx(0.01)
    ctrl.compute(ControlInputs(T, 0.0, big, EST))
    # F̂ integrates the applied (clipped) torque: b·0.01·T.
    assert ctrl.velocity_estimate == pytest.approx(B * 0.01 * T)


def test_parameters() -> None:
    ctrl = GpiController.from_parameters(B, T, {'omega_n': 50, 'pole': 20.0})
    assert isinstance(ctrl, AxisController)
    assert ctrl.alphas[0] == pytest.approx(2500.0 * 20.0)
    with pytest.raises(ParameterError, match=r'gpi\.zeta'):
        GpiController.from_parameters(B, T, {'zeta': -1.0})
    with pytest.raises(ParameterError, match='input_gain'):
        GpiController(0.0, T)
