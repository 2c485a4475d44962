"""Each law's gains pinned to a response computed here from the paper's equations.

The laws run in closed loop on the nominal plant, simulated exactly (zero-order hold,
matrix exponential); the expected response is the paper's error dynamics, solved by
scipy.signal from the printed polynomial, not from the law's code. A gain off by 10 %
moves the response by far more than the tolerance, in well under a second of CPU.
"""

from __future__ import annotations

import dataclasses

import numpy as np
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
