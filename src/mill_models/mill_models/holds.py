"""Discretisation under a β fractional-order hold (β-FROH), Rubio 2013 eq. (4)-(6) (ROS-free).

The β-FROH reconstructs the input between samples as

    u(kT + τ) = u_k + β·(u_k − u_{k−1})·τ/T,   0 ≤ τ < T,   β ∈ [−1, 1],

β = 0 being the zero-order hold. Its transfer function is
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

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.signal

from mill_models.force_process import affine_input_exponential

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
        return scipy.signal.lfilter(self.num, self.den, u)


def as_state_space(system: Sequence) -> StateSpace:
    """(num, den) in s (highest power first) or (A, B, C, D) → float arrays (A, B, C, D)."""
    if len(system) == 2:
        a, b, c, d = scipy.signal.tf2ss(
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
    num, den = scipy.signal.ss2tf(ad, bd, cd, dd)
    num = np.asarray(num, dtype=float).reshape(-1)
    den = np.asarray(den, dtype=float).reshape(-1)
    num = np.concatenate([np.zeros(len(den) - len(num)), num])
    lead = den[0]
    return DiscreteTF(num / lead, den / lead, float(T), float(beta))


def hold_input(u_k: float, u_prev: float, beta: float, T: float) -> tuple[float, float]:
    """(u0, slope) of the β-FROH reconstruction u(kT + τ) = u0 + slope·τ over [0, T)."""
    # β-FROH: u(kT + τ) = u_k + β (u_k − u_{k−1}) τ / T
    return float(u_k), float(beta) * (float(u_k) - float(u_prev)) / float(T)
