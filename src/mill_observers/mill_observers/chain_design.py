"""The discrete design of an extended-state observer on a chain of integrators. ROS-free.

Every extended-state observer here (the GPI observer of Beltrán 2013, the bandwidth-tuned
ESO) models one axis as ẍ = b·τ + ξ with ξ a Taylor polynomial: n states [x, v, ξ, ξ', …],
a chain of integrators. `ChainDesign` samples that model exactly (zero-order hold on τ) and
places the discrete error poles at z_i = exp(s_i·T) for given continuous poles s_i, so
that between samples the error decays as the continuous design would.

Conditioning: the chain spans T⁰..T^(n−1) in raw units. Design and run-time both use the
scaled state z_j = T^j·x_j, in which the sampled model is the Pascal-like matrix exp(N) (N
the unit shift); the gain is placed on W = exp(N) − I (a delta-operator form) with roots
w_i = expm1(s_i·T), so nothing cancels even when T is small.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np
from numpy.polynomial import polynomial as npoly


def _expm1_complex(s: complex) -> complex:
    """exp(s) − 1 without cancellation when |s| is small."""
    re, im = s.real, s.imag
    # exp(a+jb) − 1 = expm1(a)·cos b + (cos b − 1) + j·exp(a)·sin b, cos b − 1 = −2 sin²(b/2)
    return complex(
        math.expm1(re) * math.cos(im) - 2.0 * math.sin(0.5 * im) ** 2,
        math.exp(re) * math.sin(im),
    )


def _exp_nilpotent(m: np.ndarray) -> np.ndarray:
    """exp(M) of a nilpotent M (Mⁿ = 0 for n × n): the series stops, Σ_{k<n} Mᵏ/k!, exact.

    The model is a chain of integrators, so its ZOH sampling needs no general matrix
    exponential (and the observer process no scipy.linalg, about 20 MB)."""
    n = m.shape[0]
    out, term = np.eye(n), np.eye(n)
    for k in range(1, n):
        term = term @ m / k
        out = out + term
    if np.any(term @ m):
        raise ValueError('the matrix is not nilpotent')
    return out


class ChainDesign:
    """Sampled model and gains of an n-state chain observer (scaled units, see above)."""

    def __init__(self, n: int, b: float, T: float, s_roots: Iterable[complex]) -> None:
        # Scaling z = S·x, S = diag(T^j): raw ↔ scaled for vectors and matrices.
        self.scale = T ** np.arange(n, dtype=float)

        # Beltrán 2013 eq. (14) in scaled form: ż = (N/T)·z + b·T·e₁·τ, y = z₀.
        shift = np.eye(n, k=1)
        augmented = np.zeros((n + 1, n + 1))
        augmented[:n, :n] = shift
        augmented[1, n] = 1.0
        # Exact ZOH sampling over one period (dimensionless: N/T·T = N).
        phi = _exp_nilpotent(augmented)
        self.ad_s = phi[:n, :n]  # exp(N): entries 1/(j−i)!
        self.bd_s = (b * T * T) * phi[:n, n]  # b·T²·[1/2, 1, 0, …]
        # W = exp(N) − I summed directly (strictly upper triangular, no subtraction of 1).
        w_mat = np.triu(self.ad_s, k=1)

        # Designed discrete poles, kept as w_i = z_i − 1 for accuracy.
        w_roots = np.array([_expm1_complex(complex(s) * T) for s in s_roots])
        psi = npoly.polyfromroots(w_roots)  # ψ(w) = Π (w − w_i), low → high
        psi = psi.real  # conjugate pairs: the imaginary parts are rounding only

        # Ackermann for the observer pair (W, e₀ᵀ): L = ψ(W)·O⁻¹·e_{n−1}.
        # Eig(Ad − L C) = 1 + eig(W − L C), so placing W's poles at w_i places Ad's at z_i.
        psi_w = np.zeros((n, n))
        for c in psi[::-1]:  # Horner; Wⁿ = 0 so the leading term vanishes exactly
            psi_w = psi_w @ w_mat + c * np.eye(n)
        obs = np.empty((n, n))
        row = np.zeros(n)
        row[0] = 1.0
        for k in range(n):
            obs[k] = row
            row = row @ w_mat
        # O(W, e₀ᵀ) is unit upper triangular: triangular solve, perfectly conditioned.
        last = np.zeros(n)
        last[-1] = 1.0
        self.l_s = psi_w @ np.linalg.solve(obs, last)
        # Current-estimator gain M = Ad⁻¹·L; exp(N)⁻¹ = exp(−N) exactly.
        ad_inv = _exp_nilpotent(-shift)
        self.m_s = ad_inv @ self.l_s
        self.w_roots = w_roots


def advance(z: list[float], g0: float, g1: float, u: float, periods: float) -> list[float]:
    """The scaled chain state `periods` sample periods on (any real number) with u held:
    z⁺_i = Σ_{j≥i} z_j·r^(j−i)/(j−i)! plus b·T²·[r²/2, r] on the first two (r = periods)."""
    n = len(z)
    powers = [periods**k for k in range(n)]
    out = []
    for i in range(n):
        acc = z[i]
        for j in range(i + 1, n):
            acc += z[j] * powers[j - i] / math.factorial(j - i)
        out.append(acc)
    out[0] += g0 * u * powers[2] if n > 2 else 0.0
    out[1] += g1 * u * periods
    return out


class ChainObserver:
    """What the observers on a chain of integrators share beyond their design: the state
    `_z` in scaled units (z_j = T^j x_j), b `_b`, T `_T`, the input column `_g0`, `_g1`."""

    _b: float
    _T: float
    _z: list[float]
    _g0: float
    _g1: float
    _initialised: bool

    def elapse(self, u: float, periods: float) -> None:
        """Run the model on for a fraction of a period (a tick early or late) with u held."""
        if self._initialised and math.isfinite(u):
            self._z = advance(self._z, self._g0, self._g1, u, periods)

    def preload(self, hold_input: float) -> float | None:
        if not (self._initialised and math.isfinite(hold_input)):
            return None
        disturbance = -self._b * hold_input  # at rest: 0 = b·u + ξ
        self._z[2] = disturbance * self._T * self._T  # scaled: z₂ = T²·ξ
        return disturbance


def continuous_interval(
    n: int, b: float, T: float, s_roots: Iterable[complex]
) -> tuple[np.ndarray, ...]:
    """The continuous observer ż = A z + B τ + ℓ (y − z₀) (Beltrán 2013 eq. (15), poles
    s_i) integrated exactly over one period, in the scaled state: (Φ, Γ_u, Γ_y, Γ_d, Γ_c)
    with, for the command u(k−1) held over the period (as the drive holds it) and the
    position y(τ) = y(k−1) + d·τ + c·τ² over τ = t/T − (k−1) ∈ [0, 1],

        z(k) = Φ z(k−1) + Γ_u u(k−1) + Γ_y y(k−1) + Γ_d d + Γ_c c.

    In τ the gains are the coefficients of Π(σ − s_i·T), of order one, where the raw
    β0 is about 8·10¹⁹: the (n + 4)-square exponential is well conditioned."""
    import scipy.linalg  # only this discretisation needs it (about 20 MB)

    ell = npoly.polyfromroots([complex(s) * T for s in s_roots]).real[-2::-1]  # ℓ₀ … ℓ_{n−1}
    m = np.zeros((n + 4, n + 4))  # [z, u, y, y', c]: u and c constant, y'' = 2c
    m[:n, :n] = np.eye(n, k=1)
    m[:n, 0] -= ell
    m[1, n] = b * T * T
    m[:n, n + 1] = ell
    m[n + 1, n + 2] = 1.0
    m[n + 2, n + 3] = 2.0
    phi = scipy.linalg.expm(m)
    return phi[:n, :n], phi[:n, n], phi[:n, n + 1], phi[:n, n + 2], phi[:n, n + 3]
