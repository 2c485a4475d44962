"""The reference model of Rubio 2013 eq. (7) and its continuous response (ROS-free).

    G_m(s) = ω_n²/(s² + 2ξω_n s + ω_n²),   ω_n = 2.5/T_r   (§2.3)

with ξ = 0.7 and the rise time T_r = 3 spindle periods in the paper (§5: ω_n ≈ 9.93 rad/s
at 715 rpm). The force controller (mill_controllers.model_reference) discretises it under
the same β-hold as the plant and makes the loop follow it; the continuous response to the
reference held over each sample, F_pm(t), is what the cost J_c of eq. (14) compares the
force with between the samples (the multi-model index, the offline loop and the job
analysis all evaluate it with ContinuousReference).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np


def natural_frequency(rise_time: float) -> float:
    """ω_n = 2.5/T_r [rad/s], Rubio 2013 §2.3."""
    # Rubio 2013 §2.3: ω_n = 2.5/T_r (rise time T_r of the second-order model eq. (7))
    return 2.5 / rise_time


def reference_model(damping: float, omega_n: float) -> tuple[np.ndarray, np.ndarray]:
    """(num, den) in s of eq. (7)."""
    # Rubio 2013 eq. (7): G_m(s) = ω_n² / (s² + 2ξω_n s + ω_n²)
    return np.array([omega_n**2]), np.array([1.0, 2.0 * damping * omega_n, omega_n**2])


def reference_state_space(damping: float, omega_n: float) -> tuple[np.ndarray, ...]:
    """(A, B, C) of eq. (7), state [F_m, Ḟ_m], for its continuous response."""
    # Rubio 2013 eq. (7) in state space: F̈_m = −2ξω_n Ḟ_m − ω_n² F_m + ω_n² F_r
    a = np.array([[0.0, 1.0], [-(omega_n**2), -2.0 * damping * omega_n]])
    b = np.array([0.0, omega_n**2])
    c = np.array([1.0, 0.0])
    return a, b, c


class ContinuousReference:
    """Continuous response F_pm(t) of eq. (7) to a reference held constant over each sample.

    begin(r) fixes the input from the current time; values(times) evaluates the response
    at absolute times in the current interval (closed form); advance(h) moves on by h.
    """

    def __init__(self, damping: float, omega_n: float) -> None:
        self.a, self.b, self.c = reference_state_space(damping, omega_n)
        self._x = np.zeros(2)
        self._t = 0.0
        self._r = 0.0
        # e^{Aτ} = e^{mτ}[C(τ)·I + S(τ)·(A − m I)], m = tr A/2, q² = m² − det A
        self._m = 0.5 * float(np.trace(self.a))
        self._q = complex(self._m**2 - float(np.linalg.det(self.a))) ** 0.5

    def reset(self, value: float = 0.0, t: float = 0.0) -> None:
        """At rest at `value` [N] (steady state) at time t."""
        self._x = np.array([float(value), 0.0])
        self._t = float(t)
        self._r = float(value)

    @property
    def time(self) -> float:
        return self._t

    @property
    def state(self) -> np.ndarray:
        return self._x.copy()

    def set_state(self, state: Sequence[float], t: float) -> None:
        self._x = np.asarray(state, dtype=float).reshape(2).copy()
        self._t = float(t)

    def begin(self, reference: float) -> None:
        if not math.isfinite(reference):
            raise ValueError(f'reference must be finite, got {reference!r}')
        self._r = float(reference)

    def _states(self, tau: np.ndarray) -> np.ndarray:
        tau = np.asarray(tau, dtype=float)
        q = self._q
        qt = q * tau
        cc = np.cosh(qt).real
        ss = (np.sinh(qt) / q).real if abs(q) > 1e-12 else tau.copy()
        em = np.exp(self._m * tau)
        x_ss = np.array([self._r, 0.0])  # unit DC gain: steady state [r, 0]
        dx = self._x - x_ss
        n = self.a - self._m * np.eye(2)
        nd = n @ dx
        return x_ss[None, :] + em[:, None] * (cc[:, None] * dx[None, :] + ss[:, None] * nd)

    def values(self, times: np.ndarray) -> np.ndarray:
        """F_pm at absolute times (>= the interval start) [N]."""
        tau = np.atleast_1d(np.asarray(times, dtype=float)) - self._t
        return self._states(tau) @ self.c

    def advance(self, h: float) -> None:
        self._x = self._states(np.array([h]))[0]
        self._t += h
