"""Recursive least squares with exponential forgetting, Hatwesh 2013 eq. (10)-(13) (ROS-free).

Two role packages run this estimator: the adaptive PI (mill_controllers.adaptive_pi) with its
own copy, and the rls observer (mill_observers.rls_observer); both take RlsParams.

Model (reading of eq. (11)-(12)): a first-order plant with an input delay line,

    y(k) = a·y(k−1) + Σ_{i=1..m} b_i·u(k−i),      θ = [a, b_1, …, b_m],

so h(k) = [y(k−1), u(k−1), …, u(k−m)]. Eq. (12) prints h with −y(k−1) but the model's
denominator 1 − a q⁻¹; the signs are made consistent here (a > 0 is the sampled pole).
With m = 1 this is eq. (11)'s FOPDT with zero dead time; with m > 1, the leading taps of
a dead time d tend to zero ("RLS estimation approaches to zero for unwanted parameters"),
which is how the dead time is read off.

Load term (`load_term`, on by default): y(k) = a y(k−1) + Σ b_i u(k−i) + c, h(k) ends with 1
and θ with c. Eq. (12) as printed has no constant, so a constant load torque can only bias
a and b. The paper's text allows one: "the disturbance ... [is] captured with different
models as shown in [19]" (Lin & Lee: FOPDT processes with a class of deterministic
disturbances), and a constant load is the zero-frequency member of that class. c is read
out as the input that balances it, load = −c/Σ b_i [V] (load torque / (K_a K_t) on the drive);
it is not projected. load_term false is eq. (12) as printed.

Update (the standard form; eq. (13) prints a minus sign and a power ρ^(k−1)):

    ε(k) = y(k) − θ̂ᵀ(k−1) h(k)
    g(k) = P(k−1) h(k) / (λ + hᵀ(k) P(k−1) h(k))
    θ̂(k) = θ̂(k−1) + g(k) ε(k)
    P(k) = (P(k−1) − g(k) hᵀ(k) P(k−1)) / λ

then θ̂ is projected (clipped) onto the box a ∈ [a_min, a_max], b_i ∈ [b_min, b_max],
and P is scaled down if its trace exceeds a limit (covariance wind-up guard when the
signals are not exciting).

FOPDT read-out (eq. (11): a = e^{−T_s/τ}, b = K(1 − a)):
    K = Σ b_i / (1 − a),  τ = −T_s / ln a,
    dead time d = Σ (i−1)·b_i / Σ b_i samples (the b-weighted centroid of the delay line:
    exactly d for a pure d-sample delay, fractional for a delay between samples),
    θ_d = d·T_s.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from mill_common.declared import ParamSet, param
from mill_common.parameters import (
    ParamSpec,
    boolean,
    in_range,
    number,
    positive,
    whole_in,
)
from mill_common.signals import FopdtEstimate

__all__ = ['RLS_PARAMETERS', 'RlsEstimator', 'RlsParams']


def _pair(value: object) -> str | None:
    if not isinstance(value, list | tuple) or len(value) != 2:
        return 'must be a list [low, high]'
    reason = number(value[0]) or number(value[1])
    if reason:
        return reason
    return None if value[0] < value[1] else 'must have low < high'


@dataclass(frozen=True)
class RlsParams(ParamSet):
    """The estimator's parameters, shared by every user: each declares them under its own
    PREFIX by a subclass (the rls observer) or by RLS_PARAMETERS (adaptive_pi)."""

    forgetting: float = param(
        0.9995,
        'RLS forgetting factor λ (memory ≈ T/(1 − λ), 0.5 s at 0.25 ms)',
        in_range(0.9, 1.0),
        unit='-',
    )
    initial_covariance: float = param(1e4, 'RLS initial covariance P(0) = p0·I', positive, unit='-')
    covariance_limit: float = param(1e8, 'RLS cap on trace(P) (wind-up guard)', positive, unit='-')
    input_taps: int = param(
        2,
        'RLS input taps m of y(k) = a y(k−1) + Σ_{i≤m} b_i u(k−i); dead time up to m−1 samples',
        whole_in(1, 32),
        unit='-',
    )
    load_term: bool = param(
        True,
        'RLS model with a constant (load) term c, y(k) = a y(k−1) + Σ b_i u(k−i) + c (the '
        "reading of the paper's disturbance models); false = eq. (12) as printed, no c",
        boolean,
    )
    a_bounds: list[float] = param(
        [0.0, 0.99999], 'projection box of the RLS pole a = e^{−T/τ}', _pair, unit='-'
    )
    b_bounds: list[float] = param(
        [-1.0, 1.0],
        'projection box of each RLS input coefficient b_i',
        _pair,
        unit='(m/s)/V per sample',
    )


# The same parameters as specs, for a user that lists them among its own (adaptive_pi).
RLS_PARAMETERS: tuple[ParamSpec, ...] = RlsParams.specs()


class RlsEstimator:
    """θ = [a, b_1..b_m(, c)] of y(k) = a y(k−1) + Σ b_i u(k−i) (+ c), forgetting and bounds.

    Call update(y, u) once per sample with the new output y(k) and the input u(k) that will
    be applied from k on (it enters the regressor of later samples).
    """

    def __init__(
        self,
        sample_period: float,
        n_b: int = 1,
        forgetting: float = 0.995,
        initial_covariance: float = 1e4,
        initial_theta: Sequence[float] | None = None,
        a_bounds: tuple[float, float] = (0.0, 0.999999),
        b_bounds: tuple[float, float] = (-1e6, 1e6),
        covariance_limit: float = 1e8,
        load_term: bool = False,
    ) -> None:
        if not (sample_period > 0 and math.isfinite(sample_period)):
            raise ValueError(f'sample_period must be > 0, got {sample_period!r}')
        if not isinstance(n_b, int) or n_b < 1:
            raise ValueError(f'n_b must be a whole number >= 1, got {n_b!r}')
        if not 0.0 < forgetting <= 1.0:
            raise ValueError(f'forgetting factor must be in (0, 1], got {forgetting!r}')
        if not initial_covariance > 0:
            raise ValueError(f'initial_covariance must be > 0, got {initial_covariance!r}')
        if not (a_bounds[0] < a_bounds[1] and b_bounds[0] < b_bounds[1]):
            raise ValueError('bounds must be (low, high) with low < high')
        if not covariance_limit > 0:
            raise ValueError(f'covariance_limit must be > 0, got {covariance_limit!r}')
        self._T = float(sample_period)
        self._m = n_b
        self._c = bool(load_term)  # θ ends with the constant c, h(k) with 1
        self._lam = float(forgetting)
        self._p0 = float(initial_covariance)
        c_box = [(-math.inf, math.inf)] if self._c else []
        box = [a_bounds, *[b_bounds] * n_b, *c_box]
        self._lo = np.array([lo for lo, _ in box], dtype=float)
        self._hi = np.array([hi for _, hi in box], dtype=float)
        self._p_limit = float(covariance_limit)
        n = len(box)
        if initial_theta is None:
            theta0 = np.zeros(n)
            theta0[0] = 0.5 * (a_bounds[0] + a_bounds[1])
        else:
            theta0 = np.asarray(initial_theta, dtype=float)
            if theta0.shape != (n,):
                raise ValueError(f'initial_theta must have {n} entries')
        self._theta0 = np.clip(theta0, self._lo, self._hi)
        self.reset()

    @classmethod
    def from_params(cls, sample_period: float, p: RlsParams) -> RlsEstimator:
        """From the declared parameters (the one place their names meet the class)."""
        return cls(
            sample_period,
            n_b=p.input_taps,
            forgetting=p.forgetting,
            initial_covariance=p.initial_covariance,
            a_bounds=(p.a_bounds[0], p.a_bounds[1]),
            b_bounds=(p.b_bounds[0], p.b_bounds[1]),
            covariance_limit=p.covariance_limit,
            load_term=p.load_term,
        )

    @classmethod
    def from_parameters(cls, sample_period: float, v: Mapping[str, Any]) -> RlsEstimator:
        """From a user's values that include the RLS_PARAMETERS names (others are ignored)."""
        return cls.from_params(sample_period, RlsParams.from_node_values(v))

    def reset(self) -> None:
        """Back to θ̂(0), P(0) = p0·I; the regressor history is forgotten."""
        self._theta = self._theta0.copy()
        self._p = self._p0 * np.eye(self._theta0.size)
        self._y_prev: float | None = None
        self._u_hist = np.zeros(self._m)  # u(k−1), …, u(k−m)
        self._updates = 0
        self._last_error = 0.0
        self._err_sq = 0.0  # exponentially weighted mean of ε²
        self._clipped = False

    def update(self, y: float, u: float) -> float:
        """Feed y(k) and u(k); returns the a-priori error ε(k) (0 on the first call)."""
        if not (math.isfinite(y) and math.isfinite(u)):
            raise ValueError(f'RlsEstimator.update: non-finite sample y={y!r}, u={u!r}')
        eps = 0.0
        if self._y_prev is not None:
            # Hatwesh 2013 eq. (12): h(k) = [y(k−1), u(k−1), …, u(k−m)] (sign made consistent),
            # then 1 for the load term c
            h = np.concatenate(([self._y_prev], self._u_hist, [1.0] if self._c else []))
            # Hatwesh 2013: ε(k) = y(k) − θ̂ᵀ(k−1) h(k)
            eps = float(y - self._theta @ h)
            ph = self._p @ h
            # Hatwesh 2013 eq. (13), standard form: g = P h / (λ + hᵀ P h)
            g = ph / (self._lam + h @ ph)
            # θ̂(k) = θ̂(k−1) + g ε   (the printed minus sign read as +)
            theta = self._theta + g * eps
            clipped = np.clip(theta, self._lo, self._hi)
            self._clipped = bool(np.any(clipped != theta))
            self._theta = clipped
            # P(k) = (P − g hᵀ P)/λ, kept symmetric
            p = (self._p - np.outer(g, ph)) / self._lam
            p = 0.5 * (p + p.T)
            tr = float(np.trace(p))
            if tr > self._p_limit:
                p *= self._p_limit / tr
            self._p = p
            self._updates += 1
            self._last_error = eps
            self._err_sq = self._lam * self._err_sq + (1.0 - self._lam) * eps * eps
        self._y_prev = float(y)
        if self._m:
            self._u_hist = np.concatenate(([float(u)], self._u_hist[:-1]))
        return eps

    # --- read-outs -------------------------------------------------------------------

    @property
    def theta(self) -> np.ndarray:
        """[a, b_1, …, b_m] and, with the load term, c (a copy)."""
        return self._theta.copy()

    @property
    def covariance(self) -> np.ndarray:
        return self._p.copy()

    @property
    def sample_period(self) -> float:
        return self._T

    def fopdt(self) -> FopdtEstimate:
        """K, τ, θ_d of eq. (10)-(11) from θ̂ (see the module docstring)."""
        a = float(self._theta[0])
        b = self._theta[1 : 1 + self._m]
        b_sum = float(b.sum())
        # Hatwesh 2013 eq. (11): a = e^{−T_s/τ}, b = K (1 − a)
        gain = b_sum / (1.0 - a)
        tau = -self._T / math.log(a) if 0.0 < a < 1.0 else math.inf if a >= 1.0 else 0.0
        if b_sum != 0.0:
            d = float(np.arange(self._m) @ b) / b_sum
            d = min(max(d, 0.0), float(self._m - 1))
        else:
            d = 0.0
        return FopdtEstimate(gain, tau, d * self._T, d, self._updates)

    def load(self) -> float:
        """The input that balances the constant term, −c/Σ b_i [V] (0 without the term)."""
        if not self._c:
            return 0.0
        b_sum = float(self._theta[1 : 1 + self._m].sum())
        return -float(self._theta[-1]) / b_sum if b_sum != 0.0 else math.nan

    def diagnostics(self) -> dict[str, float]:
        """Convergence diagnostics: updates, last a-priori error, its forgetting-weighted RMS,
        trace of P, whether the last update hit a bound (1.0) or not (0.0), and the load."""
        return {
            'updates': float(self._updates),
            'last_error': self._last_error,
            'error_rms': math.sqrt(self._err_sq),
            'covariance_trace': float(np.trace(self._p)),
            'clipped': 1.0 if self._clipped else 0.0,
            'load': self.load(),
        }
