"""Each law's gains pinned to a response computed here from the paper's equations.

The laws run in closed loop on the nominal plant, simulated exactly (zero-order hold,
matrix exponential); the expected response is the paper's error dynamics, solved by
scipy.signal from the printed polynomial, not from the law's code. A gain off by 10 %
moves the response by far more than the tolerance, in well under a second of CPU.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.linalg
import scipy.signal
from mill_common.signals import AxisReference, ControlInputs, Estimate
from mill_controllers.gpi_controller import GpiController, GpiParams
from mill_controllers.sliding_gpi import SlidingGpiController, SlidingGpiParams

# Chávez-Conde section 5, x axis: b = 1/(a η1), κ = η2/η1; ζ = 0.9, ω_n = 80, μ = 15.
B, KAPPA = 0.3175056, 0.0025267
ZETA, OMEGA_N, MU = 0.9, 80.0, 15.0
T = 1e-5  # short: the continuous laws give the continuous loop to O(ω T)
X0 = 1e-3  # initial error [m]
EST = Estimate(0.0, 0.0, 0.0)
REST = AxisReference(0.0, 0.0, 0.0)


def zoh_plant(kappa: float, b: float, period: float) -> tuple[np.ndarray, np.ndarray]:
    """ẍ = −κẋ + bτ sampled exactly with the torque held: x_{k+1} = A x_k + B τ_k."""
    aug = np.zeros((3, 3))
    aug[0, 1], aug[1, 1], aug[1, 2] = 1.0, -kappa, b
    phi = scipy.linalg.expm(aug * period)
    return phi[:2, :2], phi[:2, 2]


def closed_loop(law, seconds: float, period: float = T, x0: float = X0):
    """The law on the nominal plant from x = x0 at rest, reference 0: t, x, ẋ, ∫x."""
    a, b = zoh_plant(KAPPA, B, period)
    n = round(seconds / period)
    state = np.array([x0, 0.0])
    out = np.zeros((n, 3))
    integral = 0.0
    for k in range(n):
        out[k] = state[0], state[1], integral
        tau = law.compute(ControlInputs(k * period, float(state[0]), REST, EST))
        integral += period * state[0]
        state = a @ state + b * tau
    return np.arange(n) * period, out


def error_response(poly: np.ndarray, t: np.ndarray, x0: float = X0) -> np.ndarray:
    """e(t) of e''' + c2 ë + c1 ė + c0 e = 0 with ∫e(0) = 0, e(0) = x0, ė(0) = 0: the
    paper's error dynamics, in the state [∫e, e, ė]."""
    c3, c2, c1, c0 = poly
    assert c3 == 1.0
    a = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-c0, -c1, -c2]])
    sys = scipy.signal.StateSpace(a, np.zeros((3, 1)), np.array([[0.0, 1.0, 0.0]]), 0.0)
    _, y, _ = scipy.signal.lsim(sys, np.zeros_like(t), t, X0=[0.0, x0, 0.0])
    return y


def gpi_params(discretisation: str) -> GpiParams:
    """The defaults (the paper's gains), unlimited, on the Chávez-Conde axis."""
    return dataclasses.replace(
        GpiParams(), damping_rate=KAPPA, discretisation=discretisation, torque_limit=np.inf
    )


def test_gpi_law_gives_the_cubic_of_eq_12() -> None:
    """Chávez-Conde eq. (9)-(12): the error obeys (s² + 2ζω_n s + ω_n²)(s + p), p = 80."""
    law = GpiController(B, T, gpi_params('continuous'))
    t, got = closed_loop(law, 0.1)
    want = error_response(np.polymul([1, 2 * ZETA * OMEGA_N, OMEGA_N**2], [1, 80.0]), t)
    # The sampled law is the continuous one to O(ω T) = 1e-3 of the initial error.
    assert np.max(np.abs(got[:, 0] - want)) < 3e-3 * X0


def test_gpi_law_zoh_design_places_the_sampled_roots() -> None:
    """The 1 ms ZOH design: the sampled loop equals the continuous one at the instants."""
    period = 1e-3
    law = GpiController(B, period, gpi_params('zoh'))
    t, got = closed_loop(law, 0.15, period)
    want = error_response(np.polymul([1, 2 * ZETA * OMEGA_N, OMEGA_N**2], [1, 80.0]), t)
    # Roots exp(sT) exactly; the forward-rectangle ∫e starts one sample late: O(ω T) of x0.
    assert np.max(np.abs(got[:, 0] - want)) < 0.1 * X0
    assert np.max(np.abs(got[50:, 0] - want[50:])) < 0.02 * X0


def sliding(**changes: float) -> SlidingGpiController:
    """The defaults (the paper's ζ, ω_n, μ, γ), continuous, unlimited."""
    params = dataclasses.replace(
        SlidingGpiParams(),
        damping_rate=KAPPA,
        discretisation='continuous',
        torque_limit=np.inf,
        **changes,
    )
    return SlidingGpiController(B, T, params)


def test_sliding_gpi_linear_part_is_the_surface_times_the_reaching_pole() -> None:
    """Eq. (13)-(17) with γ = 0: v = −α1 ė − α0 e − μσ, the error obeys
    (s² + α1 s + α0)(s + μ) with α1 = 2ζω_n, α0 = ω_n² (section 5)."""
    t, got = closed_loop(sliding(gamma=0.0), 0.3)
    want = error_response(np.polymul([1, 2 * ZETA * OMEGA_N, OMEGA_N**2], [1, MU]), t)
    assert np.max(np.abs(got[:, 0] - want)) < 3e-3 * X0


def test_sliding_gpi_reaches_the_surface_as_eq_16_says() -> None:
    """Eq. (16): σ̇ = −μ(σ + γ sign σ), so from σ0 > 0 σ(t) = (σ0 + γ)e^{−μt} − γ until it
    reaches 0 at t_r = ln(1 + σ0/γ)/μ; σ = ė + α1 e + α0 ∫e is computed here from the plant."""
    gamma, x0 = 10.0, 0.1  # the paper's γ [m/s]; σ0 = α1 x0 = 14.4 m/s, t_r = 59 ms
    t, got = closed_loop(sliding(), 0.1, x0=x0)
    a1, a0 = 2 * ZETA * OMEGA_N, OMEGA_N**2
    sigma = got[:, 1] + a1 * got[:, 0] + a0 * got[:, 2]
    sigma0 = a1 * x0
    want = (sigma0 + gamma) * np.exp(-MU * t) - gamma
    reaching = want > 0
    assert np.max(np.abs(sigma - want)[reaching]) < 2e-3 * sigma0
    # Sliding: σ stays within the sampled band μγT of the surface after t_r.
    reached = t > np.log(1 + sigma0 / gamma) / MU + 1e-3
    assert np.max(np.abs(sigma[reached])) < 2 * MU * gamma * T


# --- Beltrán 2013 eq. (9)-(12): PD and ADRC ------------------------------------------------

B_X = 20.96  # Beltrán x: b = 1/(a m_e) [m/s² per N·m]
XI = 2.0  # a constant disturbance [m/s²]


def beltran_loop(law, xi_hat: float, seconds: float, period: float = 1e-4):
    """ẍ = bτ + ξ from x = X0 at rest, reference 0; the law reads the true velocity."""
    a, b = zoh_plant(0.0, B_X, period)
    n = round(seconds / period)
    state, out = np.array([X0, 0.0]), np.zeros(n)
    for k in range(n):
        out[k] = state[0]
        est = Estimate(float(state[0]), float(state[1]), xi_hat)
        tau = law.compute(ControlInputs(k * period, float(state[0]), REST, est))
        state = a @ state + b * (tau + XI / B_X)  # ξ enters as an acceleration
    return np.arange(n) * period, out


def pd_response(t: np.ndarray, forced: float) -> np.ndarray:
    """e of ë + 2ζ_c ω_c ė + ω_c² e = forced, e(0) = X0, ė(0) = 0 (eq. (11)-(12), the
    paper's ζ_c = 0.7071, ω_c = 12 rad/s)."""
    zeta, omega = 0.7071, 12.0
    sys = scipy.signal.lti([1.0], [1.0, 2 * zeta * omega, omega**2])
    ss = sys.to_ss()
    # state of the controllable canonical form: [ė, e]
    _, y, _ = scipy.signal.lsim(ss, np.full_like(t, forced), t, X0=[0.0, X0 / ss.C[0, -1]])
    return y


def test_pd_law_leaves_the_static_lag_of_eq_12() -> None:
    """ξ̂ ≡ 0: the error obeys p_d(s) with the steady lag ξ/ω_c² (figs. 5-7)."""
    from mill_controllers.pd_law import PdController, PdGains

    law = PdController(B_X, 1e-4, dataclasses.replace(PdGains(), torque_limit=np.inf))
    t, got = beltran_loop(law, 0.0, 1.0)
    want = pd_response(t, XI)
    assert np.max(np.abs(got - want)) < 1e-3 * XI / 144.0
    assert got[-1] == pytest.approx(XI / 144.0, rel=0.05)


def test_adrc_law_cancels_the_disturbance_it_is_given() -> None:
    """ξ̂ = ξ: the error obeys p_d(s) unforced (figs. 8-10)."""
    from mill_controllers.pd_law import AdrcController, PdGains

    law = AdrcController(B_X, 1e-4, dataclasses.replace(PdGains(), torque_limit=np.inf))
    t, got = beltran_loop(law, XI, 1.0)
    assert np.max(np.abs(got - pd_response(t, 0.0))) < 1e-3 * X0


# --- Maharof 2018 §4.1: cascade P position / PI velocity ----------------------------------


def test_cascade_pi_step_is_the_closed_loop_of_section_4_1() -> None:
    """x/x* = G C k_v/(1 + G C (k_v + s)) with G = A/(s² + Bs + C) of eq. (1) (no dead time)
    and C(s) = k_p + k_i/s: the paper's k_v = 225 1/s, k_p = 0.00661 V·s/mm, k_i = 0.12075
    V/mm, the loop reading the true velocity; a 1 mm step of the reference."""
    from mill_controllers.cascade_pi import CascadePi, CascadePiGains

    a_, b_, c_ = 78020.0, 163.0, 193.3
    k_v, k_p, k_i = 225.0, 0.00661, 0.12075
    g = ([a_], [1.0, b_, c_])
    ctrl = ([k_p, k_i], [1.0, 0.0])
    open_num = np.polymul(g[0], ctrl[0])
    open_den = np.polymul(g[1], ctrl[1])
    closed = scipy.signal.lti(
        k_v * open_num, np.polyadd(open_den, np.polymul(open_num, [1.0, k_v]))
    )
    period, seconds = 2e-5, 0.3
    t = np.arange(round(seconds / period)) * period
    _, want = scipy.signal.step(closed, T=t)
    # the plant in mm, its input the held voltage
    aug = np.zeros((3, 3))
    aug[0, 1], aug[1, 0], aug[1, 1], aug[1, 2] = 1.0, -c_, -b_, a_
    phi = scipy.linalg.expm(aug * period)
    ad, bd = phi[:2, :2], phi[:2, 2]

    def run(reference: float, disturbance: float) -> np.ndarray:
        law = CascadePi(0.0, period, dataclasses.replace(CascadePiGains(), voltage_limit=np.inf))
        ref = AxisReference(reference * 1e-3, 0.0, 0.0)
        state, out = np.zeros(2), np.zeros(t.size)
        for k in range(t.size):
            out[k] = state[0]
            est = Estimate(state[0] * 1e-3, state[1] * 1e-3, 0.0)
            u = law.compute(ControlInputs(k * period, state[0] * 1e-3, ref, est))
            state = ad @ state + bd * (u + disturbance)
        return out

    # the sampled law lags the continuous one by about a sample at ~500 rad/s
    assert np.max(np.abs(run(1.0, 0.0) - want)) < 3e-3
    # A constant input disturbance of 1 V: x/d = G/(1 + G C (k_v + s)), cleared by k_i alone.
    _, want_d = scipy.signal.step(
        scipy.signal.lti(
            np.polymul(g[0], ctrl[1]), np.polyadd(open_den, np.polymul(open_num, [1.0, k_v]))
        ),
        T=t,
    )
    got_d = run(0.0, 1.0)
    assert np.max(np.abs(got_d - want_d)) < 0.02 * np.max(np.abs(want_d))


# --- Rubio 2013 eq. (7)-(11): the RST force law -------------------------------------------


def test_rst_force_loop_follows_the_reference_model_of_eq_7() -> None:
    """Under the ZOH (β = 0) the closed loop R, S, T around the plant is the reference model:
    its force step equals that of G_m(s) = ω_n²/(s² + 2ξω_n s + ω_n²) sampled by the ZOH,
    ξ = 0.7, ω_n = 2.5/(3T) (§2.3, §5), both discretised here by scipy; the plant is the
    unit-gain drive × process lag of eq. (1)-(3), τ_m = 0.1 s, τ_c = 1/(N_t S_s)."""
    from mill_controllers.model_reference import ForceControlDesigner, RstController
    from mill_models.force_process import ForceProcessModel

    period = 60.0 / 715.0
    tau_m, tau_c = 0.1, 1.0 / (4 * 715.0 / 60.0)
    omega_n, xi = 2.5 / (3 * period), 0.7
    plant = scipy.signal.cont2discrete(
        ([1.0], np.polymul([tau_c, 1.0], [tau_m, 1.0])), period, method='zoh'
    )
    model = scipy.signal.cont2discrete(
        ([omega_n**2], [1.0, 2 * xi * omega_n, omega_n**2]), period, method='zoh'
    )
    n = 40
    model_num = np.trim_zeros(np.ravel(model[0]), 'f')  # a leading 0 is the one-step delay
    _, (want,) = scipy.signal.dstep((model_num, model[1], period), n=n)
    law = RstController(ForceControlDesigner(ForceProcessModel()).design(0.0), gain=1.0)
    num, den = np.ravel(plant[0]), plant[1]  # y_k = (num/den) u, num[0] = 0 (strictly proper)
    y, u = np.zeros(n), np.zeros(n)
    for k in range(n):
        y[k] = sum(num[i] * u[k - i] for i in range(1, len(num)) if k >= i) - sum(
            den[i] * y[k - i] for i in range(1, len(den)) if k >= i
        )
        u[k] = law.update(1.0, float(y[k]))
    assert np.max(np.abs(y - np.ravel(want))) < 1e-9
