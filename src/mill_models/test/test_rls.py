"""RlsEstimator: converges to a known FOPDT plant, with and without noise; bounds; forgetting."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mill_models.rls import RlsEstimator

T = 0.25e-3


def _simulate(
    est: RlsEstimator, a: float, b: list[float], n: int, noise: float, seed: int, c: float = 0.0
):
    rng = np.random.default_rng(seed)
    m = len(b)
    u_hist = [0.0] * m
    y = 0.0
    for _ in range(n):
        u = float(rng.choice([-1.0, 1.0]))  # PRBS-like excitation
        y_meas = y + noise * float(rng.standard_normal())
        est.update(y_meas, u)
        # y(k+1) = a y(k) + Σ b_i u(k+1−i)
        u_hist = [u, *u_hist[:-1]]
        y = a * y + sum(bi * ui for bi, ui in zip(b, u_hist, strict=True)) + c
    return est


def test_noise_free_converges_to_the_exact_parameters() -> None:
    a, b = 0.95, [0.0, 0.25, 0.0]  # K = 5, τ = −T/ln 0.95, one sample of dead time
    # With λ = 1 the prior θ(0), P(0) = p0·I is the only bias; it fades like 1/(p0·k).
    est = _simulate(
        RlsEstimator(T, n_b=3, forgetting=1.0, initial_covariance=1e8), a, b, 2000, 0.0, 1
    )
    np.testing.assert_allclose(est.theta, [a, *b], atol=1e-9)
    m = est.fopdt()
    assert m.gain == pytest.approx(5.0, rel=1e-6)
    assert m.time_constant == pytest.approx(-T / math.log(a), rel=1e-6)
    assert m.dead_time_samples == pytest.approx(1.0, abs=1e-6)
    assert m.dead_time == pytest.approx(T, rel=1e-5)
    assert est.diagnostics()['error_rms'] < 1e-3  # decays with the forgetting weight


def test_small_noise_converges_close() -> None:
    a, b = 0.95, [0.25, 0.0]
    est = _simulate(RlsEstimator(T, n_b=2, forgetting=0.999), a, b, 20000, 0.01, 2)
    # Output noise 0.01 against a signal of ~±5: equation-error bias and noise are small.
    assert est.theta[0] == pytest.approx(a, abs=2e-3)
    assert est.fopdt().gain == pytest.approx(5.0, rel=0.03)
    assert est.fopdt().dead_time_samples < 0.05


def test_bounds_are_enforced_by_projection() -> None:
    est = RlsEstimator(T, n_b=1, forgetting=1.0, a_bounds=(0.0, 0.9), b_bounds=(0.0, 0.1))
    _simulate(est, 0.95, [0.25], 500, 0.0, 3)
    assert est.theta[0] <= 0.9
    assert est.theta[1] <= 0.1
    assert est.diagnostics()['clipped'] == 1.0


def test_forgetting_tracks_a_parameter_change() -> None:
    est = RlsEstimator(T, n_b=1, forgetting=0.98)
    _simulate(est, 0.9, [0.5], 500, 0.0, 4)
    assert est.fopdt().gain == pytest.approx(5.0, rel=1e-6)
    _simulate(est, 0.8, [0.5], 500, 0.0, 5)
    assert est.fopdt().gain == pytest.approx(2.5, rel=1e-3)


def test_rejects_bad_settings() -> None:
    with pytest.raises(ValueError):
        RlsEstimator(T, forgetting=1.5)
    with pytest.raises(ValueError):
        RlsEstimator(T, n_b=0)
    with pytest.raises(ValueError):
        RlsEstimator(T).update(math.nan, 0.0)


def test_load_term_identifies_a_constant_and_reads_it_out_as_an_input() -> None:
    a, b, c = 0.95, [0.125, 0.125], -0.01  # a load worth −c/Σb = 0.04 of input
    est = _simulate(
        RlsEstimator(T, n_b=2, forgetting=1.0, initial_covariance=1e8, load_term=True),
        a,
        b,
        2000,
        0.0,
        6,
        c,
    )
    np.testing.assert_allclose(est.theta, [a, *b, c], atol=1e-9)
    assert est.load() == pytest.approx(0.04, rel=1e-7)
    assert est.diagnostics()['load'] == est.load()
    assert est.fopdt().gain == pytest.approx(5.0, rel=1e-7)  # c does not enter K


def test_without_the_load_term_a_constant_biases_the_model() -> None:
    """Eq. (12) as printed: the same data give a wrong gain (the reason for load_term)."""
    est = _simulate(
        RlsEstimator(T, n_b=2, forgetting=1.0, initial_covariance=1e8),
        0.95,
        [0.125, 0.125],
        2000,
        0.0,
        6,
        -0.01,
    )
    assert est.load() == 0.0
    assert abs(est.fopdt().gain / 5.0 - 1.0) > 0.05  # measured +9.9 %
