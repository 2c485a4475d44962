"""GPI controller with an integral state reconstructor, Chávez-Conde eq. (9)-(12) (ROS-free).

Position output feedback only: the velocity is reconstructed from the applied torque and
the measured position, so the controller needs no observer (`est` is ignored).

Model (Chávez-Conde eq. (7), divided by η1): ẍ = −κ ẋ + b τ + ξ/η1, with b = 1/(a η1)
the suite's input gain and κ = η2/η1 = d2/d1 the viscous rate (parameter damping_rate).

Readings:

- Eq. (10) prints F̂ = (1/d1)∫u − (d2/d1) F. We subtract the initial position,
  F̂ = b ∫₀ᵗ τ − κ (F − F(0)), so that eq. (11), Ḟ = F̂ + Ḟ(0), holds exactly; the
  printed form differs only by the constant κ F(0), which the integral term absorbs anyway.
- Eq. (12) prints the gains α1, α0, α0 and the characteristic polynomial
  s³ + α1 s² + α2 s + α0 (mixed names). The error dynamics of (12) are
  e⁽³⁾ + α2 ë + α1 ė + α0 e = 0, so (12) reads
  v = F̈* − α2 (F̂ − Ḟ*) − α1 (F − F*) − α0 ∫(F − F*).
- The paper gives only the quadratic s² + 2ζω_n s + ω_n² (ζ = 0.9, ω_n = 80, for eq. (15));
  the cubic needs a third root. We use (s² + 2ζω_n s + ω_n²)(s + p) with p = pole, default
  80 rad/s (= ω_n): all three roots at radius ≈ ω_n, none slower than the quadratic's.
- With a constant disturbance ξ the reconstructed velocity drifts by ∫ξ/η1 (a ramp) and the
  single error integral leaves the steady error e = (α2 − κ) ξ / (η1 α0): the paper's
  observation that GPI alone "needs more robustness" (section 6).
- The reconstructor offset F̂ − Ḟ = −Ḟ(0) is invariant (a root s = 0 of the full state
  [x, ẋ, ∫τ, ∫e]), but it is neither reachable from nor seen at the input-output level:
  from y to τ the law is the first-order lead compensator
  τ = −(1/b)·((α1 − (α2 − κ)κ) s + α0)/(s + α2 − κ)·y (+ feed-forward), and plant plus
  compensator have exactly the three designed roots.

Discretisation (sample period T, torque held constant over each sample, zero-order hold).
Parameter `discretisation`: 'zoh' (default) designs discrete gains k for the sampled loop;
'continuous' runs the continuous law of the paper, gains α as printed, evaluated once per
sample (the paper ran it inside a fixed-step 1 ms Simulink model): at a short T (0.1 ms on
Chávez-Conde) it reproduces the continuous closed loop; at 1 ms the forward rectangle moves
the roots (below). Both accumulate the integrals the same way:

- ∫τ is accumulated exactly: ∫ over [t_{k−1}, t_k] of the held torque is (t_k − t_{k−1})
  τ_{k−1}, with τ_{k−1} the torque actually returned (after the torque limit). On the
  nominal plant F̂_k therefore equals ẋ(t_k) − ẋ(0) exactly, saturated or not.
- ∫e is a forward rectangle: I_k = I_{k−1} + (t_k − t_{k−1}) e_{k−1} (strictly causal).
- The gains (k0, k1, k2) that replace (α0, α1, α2) are designed on the exactly sampled
  error model [I, e, ė] (ZOH, including κ) so that the closed-loop roots are exactly
  z_i = exp(s_i T), s_i the designed continuous roots; they tend to (α0, α1, α2) as T → 0
  (at T = 1 ms, ζ = 0.9, ω_n = p = 80: k = (458025, 16497, 208.7) against
  α = (512000, 17920, 224), 7-11 % lower). Using the continuous α directly at 1 ms would
  move the roots to −117, −63 ± 32j (forward rectangle) or −79, −82 ± 26j (backward
  rectangle) instead of the designed −80, −72 ± 35j.
- Elapsed times come from the t passed to compute(); a repeated call at the same t
  integrates nothing (idempotent), a t that goes backwards raises ValueError.

Non-finite inputs raise ValueError (the node catches and logs it), as in pd_law.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from mill_common.declared import param
from mill_common.parameters import non_negative, one_of, positive
from mill_common.signals import AxisReference, ControlInputs

from mill_controllers.base import AxisController, check_gain_and_period, saturate
from mill_controllers.pd_law import TorqueLimited

DISCRETISATIONS = ('zoh', 'continuous')


@dataclass(frozen=True)
class GpiShared(TorqueLimited):
    """What the GPI laws share: the nominal model's viscous rate and the discretisation."""

    damping_rate: float = param(
        0.0,
        'viscous rate κ = η2/η1 = d2/d1 of the nominal model ẍ = −κẋ + bτ + ξ [1/s]; '
        '0 leaves viscous friction to the disturbance (κ = 0.0025 on Chávez-Conde x, '
        '0.053 on Beltrán x, with c_t read as translational)',
        non_negative,
    )
    discretisation: str = param(
        'zoh',
        "'zoh': gains designed on the exactly sampled loop (roots exp(s T)); 'continuous': "
        "the paper's continuous gains α evaluated each sample (for a short sample period)",
        one_of(*DISCRETISATIONS),
    )


@dataclass(frozen=True)
class GpiParams(GpiShared):
    """The GPI law's parameters: the cubic error polynomial (s² + 2ζω_n s + ω_n²)(s + p)."""

    PREFIX: ClassVar[str] = 'gpi'
    omega_n: float = param(
        80.0,
        'natural frequency ω_n of the quadratic factor of the error polynomial',
        positive,
        unit='rad/s',
    )
    zeta: float = param(0.9, 'damping ratio ζ of the quadratic factor', positive, unit='-')
    pole: float = param(
        80.0,
        'third (real) root of the cubic error polynomial, at s = −pole',
        positive,
        unit='rad/s',
    )


def quadratic_roots(omega_n: float, zeta: float) -> list[complex]:
    """Roots of s² + 2ζω_n s + ω_n² (Chávez-Conde section 5)."""
    disc = complex(zeta * zeta - 1.0)
    root = omega_n * disc**0.5
    return [-zeta * omega_n + root, -zeta * omega_n - root]


def discrete_gpi_gains(
    damping_rate: float, sample_period: float, roots: Sequence[complex]
) -> tuple[float, float, float]:
    """Gains (k0, k1, k2) of u = (1/b)[F̈* + κḞ* − (k2 − κ)(F̂ − Ḟ*) − k1 e − k0 I].

    Placed on the exactly sampled error model so that the roots of the sampled loop are
    exp(s_i T) for the three continuous roots s_i. State X = [I, e, ė]:
    I_{k+1} = I_k + T e_k, [e, ė]_{k+1} = ZOH(ë = −κė + b u_fb).
    """
    T, kappa = float(sample_period), float(damping_rate)  # b only scales u: not needed
    # Scaled state [I/T, e, T ė] and input T² b u_fb keep every entry O(1) for small T.
    cont = np.zeros((3, 3))
    cont[0, 1] = 1.0
    cont[1, 2] = 1.0
    cont[2, 2] = -kappa * T
    aug = np.zeros((4, 4))
    aug[:3, :3] = cont
    aug[2, 3] = 1.0
    import scipy.linalg  # here: the other laws' processes need not load it (about 20 MB)

    phi = scipy.linalg.expm(aug)  # exact ZOH of d/dτ (τ = t/T) for e, ė; I is summed
    a_d = phi[:3, :3]
    b_d = phi[:3, 3].copy()
    # I is a forward rectangle, not the integral of e: I_{k+1}/T = I_k/T + e_k.
    a_d[0, :] = [1.0, 1.0, 0.0]
    b_d[0] = 0.0
    z = [complex(np.exp(complex(s) * T)) for s in roots]
    char = np.real(np.poly(z))  # monic, high → low
    phi_a = char[0] * np.linalg.matrix_power(a_d, 3)
    phi_a += char[1] * (a_d @ a_d) + char[2] * a_d + char[3] * np.eye(3)
    ctrb = np.column_stack([b_d, a_d @ b_d, a_d @ a_d @ b_d])
    k_scaled = np.linalg.solve(ctrb.T, np.array([0.0, 0.0, 1.0])) @ phi_a  # Ackermann
    # b u_fb = −(k_scaled/T²)·[I/T, e, T ė] = −(k0 I + k1 e + (k2 − κ) ė)
    k0 = float(k_scaled[0]) / T**3
    k1 = float(k_scaled[1]) / T**2
    k2 = float(k_scaled[2]) / T + kappa
    return k0, k1, k2


class GpiController(AxisController):
    """Chávez-Conde eq. (12) for one axis: position feedback, velocity reconstructed."""

    # GpiShared: SlidingGpiController declares its own set beside GpiParams
    PARAMS: ClassVar[type[GpiShared]] = GpiParams

    def __init__(
        self, input_gain: float, sample_period: float, params: GpiParams = GpiParams()
    ) -> None:
        self._b, self._T = check_gain_and_period(input_gain, sample_period)
        self._discretisation = params.discretisation
        self._omega_n = params.omega_n
        self._zeta = params.zeta
        self._pole = params.pole
        self._kappa = params.damping_rate
        self._limit = params.torque_limit
        # Chávez-Conde eq. (12), names fixed: e⁽³⁾ + α2 ë + α1 ė + α0 e = 0 with
        # s³ + α2 s² + α1 s + α0 = (s² + 2ζω_n s + ω_n²)(s + p)
        zw = 2.0 * self._zeta * self._omega_n
        w2 = self._omega_n**2
        self._alpha = (w2 * self._pole, w2 + zw * self._pole, zw + self._pole)
        self._roots = [*quadratic_roots(self._omega_n, self._zeta), complex(-self._pole)]
        self._k = self._gains(self._alpha)
        self.reset()

    def _gains(self, alpha: tuple[float, float, float]) -> tuple[float, float, float]:
        """The gains the law runs with: α itself, or the ZOH design for the roots."""
        if self._discretisation == 'continuous':
            return alpha
        return discrete_gpi_gains(self._kappa, self._T, self._roots)

    def reset(self) -> None:
        """Forget the integrals; the next compute() takes its y as F(0)."""
        self._started = False
        self._t_prev = 0.0
        self._y0 = 0.0
        self._int_u = 0.0  # ∫τ dt [N·m·s]
        self._int_e = 0.0  # ∫e dt [m·s]
        self._u_prev = 0.0
        self._e_prev = 0.0
        self._f_hat = 0.0

    @property
    def alphas(self) -> tuple[float, float, float]:
        """Continuous gains (α0, α1, α2) of s³ + α2 s² + α1 s + α0."""
        return self._alpha

    @property
    def gains(self) -> tuple[float, float, float]:
        """Gains (k0, k1, k2) actually used: α ('continuous'), or the ZOH design (→ α as
        T → 0)."""
        return self._k

    @property
    def design_roots(self) -> list[complex]:
        """Designed continuous closed-loop roots [1/s] (the sampled loop has exp(s T))."""
        return list(self._roots)

    @property
    def velocity_estimate(self) -> float:
        """F̂ of the last compute(): ẋ − ẋ(0) reconstructed, eq. (10)-(11) [m/s]."""
        return self._f_hat

    @property
    def input_gain(self) -> float:
        return self._b

    @property
    def torque_limit(self) -> float:
        return self._limit

    def _advance(self, t: float, y: float, ref: AxisReference) -> tuple[float, float, float]:
        """Update the integrals to time t; return (e, F̂ − Ḟ*, ∫e)."""
        inputs = (t, y, ref.position, ref.velocity, ref.acceleration)
        if not all(math.isfinite(v) for v in inputs):
            raise ValueError(
                f'{type(self).__name__}: non-finite input (t={t!r}, y={y!r}, ref={ref!r})'
            )
        t, y = float(t), float(y)
        if not self._started:
            self._started = True
            self._y0 = y
            self._t_prev = t
        dt = t - self._t_prev
        if dt < 0.0:
            raise ValueError(f'{type(self).__name__}: time went backwards ({self._t_prev} → {t})')
        if dt > 0.0:
            # Exact for the held torque (ZOH); forward rectangle for the error integral.
            self._int_u += dt * self._u_prev
            self._int_e += dt * self._e_prev
            self._t_prev = t
        e = y - ref.position
        # Chávez-Conde eq. (10)-(11): F̂ = (1/d1)∫u − (d2/d1)(F − F(0)) = b∫τ − κ(F − F(0))
        self._f_hat = self._b * self._int_u - self._kappa * (y - self._y0)
        self._e_prev = e
        return e, self._f_hat - ref.velocity, self._int_e

    def _finish(self, accel: float) -> float:
        """Torque from the commanded b·τ, clipped; remembered as the applied torque."""
        tau = saturate(accel / self._b, self._limit)
        self._u_prev = tau
        return tau

    def compute(self, inputs: ControlInputs) -> float:
        """Torque [N·m] at time t from the measured position y; the estimate is not used."""
        ref = inputs.reference
        e, de_hat, int_e = self._advance(inputs.t, inputs.position, ref)
        k0, k1, k2 = self._k
        # Chávez-Conde eq. (9), (12): u = d1 v + d2 F̂,
        # v = F̈* − α2 (F̂ − Ḟ*) − α1 e − α0 ∫e, i.e. b u = v + κ F̂ (discrete gains k for α)
        v = ref.acceleration - k2 * de_hat - k1 * e - k0 * int_e
        return self._finish(v + self._kappa * self._f_hat)
