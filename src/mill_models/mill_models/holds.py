"""Holds: the β fractional-order hold of Rubio 2013 eq. (4)-(6), and the sample hold (ROS-free).

The β-FROH (β-hold) reconstructs the input between samples as

    u(kT + τ) = u_k + β·(u_k − u_{k−1})·τ/T,   0 ≤ τ < T,   β ∈ [−1, 1],

β = 0 being the zero-order hold. Everything the suite does with it is here:

- hold_input: the reconstruction over one sample as (u0, slope);
- clamped_pieces, clamped_trace: that affine input limited to a feed range, piece by piece,
  and the force process driven by it (the drive's range, used by mill_plant.force_drive
  and by HeldPlant);
- froh_discretize (froh_matrices, froh_state_space): the discrete model H_β(z) of a
  continuous plant under the hold, eq. (4)-(6), on which the force controller designs;
- HeldPlant: a force-process plant seen through the hold and the feed clamp, one control
  period at a time, with the squared error to the reference model integrated between the
  samples (the shadow loops of the multi-model schemes and the models of the tests);
- SampleHold: the other hold, for measurements: a non-finite sample is replaced by the
  last finite one.

The β-FROH's transfer function is
h_β(s) = (1 − β e^{−sT} + β(1 − e^{−sT})/(Ts))·(1 − e^{−sT})/s (eq. (5) prints the last
factor over Ts; with 1/s, as in eq. (6)'s h_o(s), β = 0 gives the usual ZOH).

Instead of the Z-transforms of eq. (6) the plant is sampled exactly in state space: with
Φ = e^{AT}, Γ0 = ∫0^T e^{Aσ}dσ·B and Γ1 = (1/T)∫0^T e^{A(T−σ)}σ dσ·B,

    x_{k+1} = Φ x_k + (Γ0 + βΓ1)·u_k − βΓ1·u_{k−1},

so for β ≠ 0 the state grows by u_{k−1} and the discrete model gains a pole at z = 0
(eq. (6), δ_β = 1). The poles are e^{−T/τ} (eq. (6) prints e^{T/τ}: a misprint).

Transfer functions are returned as polynomials in z, highest power first (the
scipy.signal convention), the denominator monic and the numerator padded to its length.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mill_models.force_process import ForceProcessPlant, affine_input_exponential
from mill_models.quadrature import simpson
from mill_models.reference_model import ContinuousReference

StateSpace = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


@dataclass(frozen=True)
class DiscreteTF:
    """H(z) = num(z)/den(z), polynomials in z highest power first, den monic, same length."""

    num: np.ndarray
    den: np.ndarray
    dt: float
    beta: float

    @property
    def order(self) -> int:
        return len(self.den) - 1

    def zeros(self) -> np.ndarray:
        return np.roots(np.trim_zeros(self.num, 'f')) if np.any(self.num) else np.array([])

    def poles(self) -> np.ndarray:
        return np.roots(self.den)

    def dc_gain(self) -> float:
        return float(np.polyval(self.num, 1.0) / np.polyval(self.den, 1.0))

    def step_response(self, n: int, amplitude: float = 1.0) -> np.ndarray:
        """Output samples y_0..y_{n−1} for u_k = amplitude (k ≥ 0), zero initial state."""
        u = np.full(n, float(amplitude))
        from scipy.signal import lfilter  # slow to load: only where a hold is run

        return lfilter(self.num, self.den, u)


def as_state_space(system: Sequence) -> StateSpace:
    """(num, den) in s (highest power first) or (A, B, C, D) → float arrays (A, B, C, D)."""
    if len(system) == 2:
        from scipy.signal import tf2ss

        a, b, c, d = tf2ss(
            np.atleast_1d(np.asarray(system[0], dtype=float)),
            np.atleast_1d(np.asarray(system[1], dtype=float)),
        )
    elif len(system) == 4:
        a, b, c, d = (np.atleast_2d(np.asarray(m, dtype=float)) for m in system)
    else:
        raise ValueError('system must be (num, den) or (A, B, C, D)')
    a = np.atleast_2d(a)
    n = a.shape[0]
    b = np.asarray(b, dtype=float).reshape(n, -1)
    c = np.asarray(c, dtype=float).reshape(-1, n)
    d = np.asarray(d, dtype=float).reshape(c.shape[0], b.shape[1])
    if b.shape[1] != 1 or c.shape[0] != 1:
        raise ValueError('only single-input single-output systems are supported')
    return a, b, c, d


def _check_beta(beta: float) -> float:
    beta = float(beta)
    if not math.isfinite(beta) or not -1.0 <= beta <= 1.0:
        raise ValueError(f'beta must be in [-1, 1], got {beta!r}')
    return beta


def _check_period(T: float) -> float:
    T = float(T)
    if not math.isfinite(T) or T <= 0.0:
        raise ValueError(f'sample period must be > 0, got {T!r}')
    return T


def froh_matrices(a: np.ndarray, b: np.ndarray, T: float) -> tuple[np.ndarray, ...]:
    """(Φ, Γ0, Γ1) of the exactly sampled ẋ = Ax + Bu under an affine input.

    x((k+1)T) = Φ x(kT) + Γ0·u(kT) + Γ1·(u((k+1)T⁻) − u(kT)).
    """
    T = _check_period(T)
    a = np.atleast_2d(np.asarray(a, dtype=float))
    n = a.shape[0]
    e = affine_input_exponential(a, np.asarray(b, dtype=float).reshape(n), T)
    return e[:n, :n], e[:n, n], e[:n, n + 1] / T


def froh_state_space(system: Sequence, T: float, beta: float) -> StateSpace:
    """Discrete (Ad, Bd, Cd, Dd) of `system` under a β-FROH.

    β = 0: state x, exactly the ZOH model. β ≠ 0: state [x; u_{k−1}].
    """
    beta = _check_beta(beta)
    a, b, c, d = as_state_space(system)
    phi, g0, g1 = froh_matrices(a, b[:, 0], T)
    n = a.shape[0]
    if beta == 0.0:
        return phi, g0.reshape(n, 1), c.copy(), d.copy()
    # Rubio 2013 eq. (4)-(5): x_{k+1} = Φx_k + (Γ0 + βΓ1)u_k − βΓ1 u_{k−1}
    ad = np.zeros((n + 1, n + 1))
    ad[:n, :n] = phi
    ad[:n, n] = -beta * g1
    bd = np.zeros((n + 1, 1))
    bd[:n, 0] = g0 + beta * g1
    bd[n, 0] = 1.0
    cd = np.zeros((1, n + 1))
    cd[0, :n] = c[0]
    return ad, bd, cd, d.copy()


def froh_discretize(system: Sequence, T: float, beta: float) -> DiscreteTF:
    """H_β(z) = Z[h_β(s)·G(s)] of Rubio 2013 eq. (4)-(6) as a DiscreteTF in z.

    `system` is (num, den) in s or (A, B, C, D). For β ≠ 0 the denominator carries the
    extra pole at z = 0 of eq. (6) (order n + 1); for β = 0 it is the ZOH model (order n).
    """
    ad, bd, cd, dd = froh_state_space(system, T, beta)
    from scipy.signal import ss2tf

    num, den = ss2tf(ad, bd, cd, dd)
    num = np.asarray(num, dtype=float).reshape(-1)
    den = np.asarray(den, dtype=float).reshape(-1)
    num = np.concatenate([np.zeros(len(den) - len(num)), num])
    lead = den[0]
    return DiscreteTF(num / lead, den / lead, float(T), float(beta))


def hold_input(u_k: float, u_prev: float, beta: float, T: float) -> tuple[float, float]:
    """(u0, slope) of the β-FROH reconstruction u(kT + τ) = u0 + slope·τ over [0, T)."""
    # Rubio 2013 eq. (5), the β-FROH in time: u(kT + τ) = u_k + β (u_k − u_{k−1}) τ / T
    return float(u_k), float(beta) * (float(u_k) - float(u_prev)) / float(T)


def clamped_pieces(
    u0: float, slope: float, duration: float, lo: float, hi: float
) -> list[tuple[float, float, float]]:
    """Split u0 + slope·τ on [0, duration] into affine pieces clamped to [lo, hi].

    Returns [(length, start value, slope)]: a piece outside the range becomes a constant
    at the bound, so the reconstructed input never leaves [lo, hi].
    """
    if lo > hi:
        raise ValueError(f'empty range [{lo}, {hi}]')
    cuts = {0.0, float(duration)}
    if slope != 0.0:
        for bound in (lo, hi):
            if math.isfinite(bound):
                tau = (bound - u0) / slope
                if 0.0 < tau < duration:
                    cuts.add(tau)
    edges = sorted(cuts)
    pieces = []
    for a, b in itertools.pairwise(edges):
        if b <= a:
            continue
        mid = u0 + slope * 0.5 * (a + b)
        start = u0 + slope * a
        if mid > hi:
            pieces.append((b - a, hi, 0.0))
        elif mid < lo:
            pieces.append((b - a, lo, 0.0))
        else:
            pieces.append((b - a, min(hi, max(lo, start)), slope))
    if not pieces:
        pieces.append((float(duration), min(hi, max(lo, u0)), 0.0))
    return pieces


def clamped_trace(
    plant: ForceProcessPlant,
    u0: float,
    slope: float,
    duration: float,
    lo: float,
    hi: float,
    spacing: float,
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Drive `plant` with u0 + slope·τ clamped to [lo, hi] for `duration` [s].

    Returns the force on a grid [(times, forces)] per smooth piece (split at clamp corners
    and depth changes) with spacing <= `spacing` (ForceProcessPlant.trace).
    """
    pieces = []
    for length, start, sl in clamped_pieces(u0, slope, duration, lo, hi):
        pieces.extend(plant.trace(start, sl, length, spacing))
    return pieces


class HeldPlant:
    """A force-process plant seen through a β-FROH and the drive's clamp on the feed.

    advance(u_k, beta) applies u(kT + τ) = u_k + β(u_k − u_{k−1})τ/T over one period,
    clamped to [lo, hi] (the plant never sees a feed outside the range), and returns the
    force at the end [N]; with a ContinuousReference it also integrates the squared error
    ∫(F_p − F_pm)² over the period (Simpson on a grid, split where the input or the depth
    changes slope or value).
    """

    def __init__(
        self,
        plant: ForceProcessPlant,
        lo: float = -math.inf,
        hi: float = math.inf,
        spacing: float | None = None,
    ) -> None:
        if not lo <= hi:
            raise ValueError(f'feed range [{lo}, {hi}] is empty')
        self.plant = plant
        self.lo = float(lo)
        self.hi = float(hi)
        self.spacing = float(spacing) if spacing else plant.model.sample_period / 16.0
        self.T = plant.model.sample_period
        self.u_prev = 0.0

    def clamp(self, u: float) -> float:
        return min(self.hi, max(self.lo, float(u)))

    def apply(
        self, u0: float, slope: float, duration: float
    ) -> list[tuple[np.ndarray, np.ndarray]]:
        """Drive the plant with u0 + slope·τ, clamped, for `duration` (clamped_trace)."""
        return clamped_trace(self.plant, u0, slope, duration, self.lo, self.hi, self.spacing)

    def advance(
        self,
        u_k: float,
        beta: float,
        reference: ContinuousReference | None = None,
        keep_trace: bool = False,
    ) -> tuple[float, float, list[tuple[np.ndarray, np.ndarray, np.ndarray]]]:
        """(force at the end [N], ∫(F_p − F_pm)² dτ [N²·s] (0 without reference), pieces).

        pieces (only with keep_trace and a reference): [(times, F_p, F_pm)].
        """
        u0, slope = hold_input(u_k, self.u_prev, beta, self.T)
        self.u_prev = float(u_k)
        cost = 0.0
        trace: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        if reference is None:  # no grid needed: one exact step per clamped piece
            for length, start, sl in clamped_pieces(u0, slope, self.T, self.lo, self.hi):
                self.plant.step(start, sl, length)
            return self.plant.force, cost, trace
        for times, force in self.apply(u0, slope, self.T):
            f_ref = reference.values(times)
            cost += simpson(times, (force - f_ref) ** 2)
            if keep_trace:
                trace.append((times, force, f_ref))
        return self.plant.force, cost, trace


class SampleHold:
    """Pass finite samples, replace a non-finite one by the last finite (initial value first)."""

    def __init__(self, initial: float = 0.0) -> None:
        self._last = float(initial)
        self.held = 0

    def __call__(self, value: float) -> float:
        if isinstance(value, int | float) and math.isfinite(value):
            self._last = float(value)
        else:
            self.held += 1
        return self._last
