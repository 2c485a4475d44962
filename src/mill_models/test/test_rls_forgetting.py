"""The RLS forgetting factor pinned to the exponentially weighted least-squares fit it
defines (Hatwesh 2013 eq. (13), standard form), computed here in one batch with numpy: after
N samples θ̂ minimises Σ λ^{N−k} ε_k² + λ^N (θ − θ0)ᵀ P0⁻¹ (θ − θ0). The plant changes
half-way, so the fit depends on λ: a factor changed in its defaults fails in a second."""

from __future__ import annotations

import numpy as np
import pytest
from mill_models.rls import RlsEstimator, RlsParams

T = 0.25e-3  # Hatwesh's sampling
LAMBDA = 0.9995  # the documented default: memory T/(1 − λ) = 0.5 s (docs/papers.md)
LAMBDA_ESTIMATOR = 0.995  # RlsEstimator's own default


def data(n: int = 4000, seed: int = 1):
    """y(k) = a y(k−1) + b1 u(k−1) + b2 u(k−2) + c, θ changing at k = n/2; u random ±1."""
    rng = np.random.default_rng(seed)
    u = rng.choice([-1.0, 1.0], size=n)
    y = np.zeros(n)
    for k in range(2, n):
        a, b1, b2, c = (0.95, 0.02, 0.01, 0.001) if k < n // 2 else (0.9, 0.04, 0.02, -0.002)
        y[k] = a * y[k - 1] + b1 * u[k - 1] + b2 * u[k - 2] + c
    return y, u


def weighted_fit(y, u, lam: float, theta0, p0: float, taps: int, load: bool) -> np.ndarray:
    """The batch minimiser of the forgetting-weighted cost, regressors of eq. (12)."""
    rows, targets = [], []
    for k in range(1, len(y)):
        past = [u[k - i] if k - i >= 0 else 0.0 for i in range(1, taps + 1)]
        rows.append([y[k - 1], *past, *([1.0] if load else [])])
        targets.append(y[k])
    h, target = np.array(rows), np.array(targets)
    n = len(target)
    w = lam ** np.arange(n - 1, -1, -1)
    prior = lam**n / p0
    lhs = h.T @ (w[:, None] * h) + prior * np.eye(h.shape[1])
    rhs = h.T @ (w * target) + prior * np.asarray(theta0)
    return np.linalg.solve(lhs, rhs)


def run(rls: RlsEstimator, y, u) -> np.ndarray:
    for yk, uk in zip(y, u, strict=True):
        rls.update(float(yk), float(uk))
    return rls.theta


def test_the_declared_default_forgets_as_lambda_0_9995() -> None:
    p = RlsParams()
    y, u = data()
    rls = RlsEstimator.from_params(T, p)
    theta0 = rls.theta
    want = weighted_fit(y, u, LAMBDA, theta0, p.initial_covariance, p.input_taps, p.load_term)
    got = run(rls, y, u)
    assert got == pytest.approx(want, rel=1e-6, abs=1e-9)


def test_the_estimators_own_default_forgets_as_lambda_0_995() -> None:
    y, u = data()
    rls = RlsEstimator(T, n_b=2, load_term=True, a_bounds=(0.0, 0.99999), b_bounds=(-1.0, 1.0))
    want = weighted_fit(y, u, LAMBDA_ESTIMATOR, rls.theta, 1e4, 2, True)
    assert run(rls, y, u) == pytest.approx(want, rel=1e-6, abs=1e-9)


def test_the_fit_depends_on_lambda() -> None:
    """The check has teeth: λ 1 % off moves the fit well beyond the tolerance above."""
    y, u = data()
    a = weighted_fit(y, u, LAMBDA, [0.5, 0, 0, 0], 1e4, 2, True)
    b = weighted_fit(y, u, 1 - 1.1 * (1 - LAMBDA), [0.5, 0, 0, 0], 1e4, 2, True)
    assert np.max(np.abs(a - b) / np.abs(a)) > 1e-3
