"""Imbdo: recovers an input disturbance on the nominal model at the Q-filter's pace."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.signal
from mill_common.parameters import ParameterError
from mill_observers.base import Observer
from mill_observers.imbdo import MAHAROF_A, MAHAROF_B, MAHAROF_C, Imbdo, ImbdoParams

T = 1e-4


def _plant(T: float) -> tuple[np.ndarray, np.ndarray]:
    """Maharof 2018 eq. (1) without dead time, ZOH-sampled; state [mm, mm/s]."""
    a = np.array([[0.0, 1.0], [-MAHAROF_C, -MAHAROF_B]])
    b = np.array([[0.0], [MAHAROF_A]])
    ad, bd, *_ = scipy.signal.cont2discrete((a, b, np.eye(2), np.zeros((2, 1))), T, 'zoh')
    return ad, bd[:, 0]


def _run_open_loop(obs: Imbdo, d_of_k, u_of_k, n: int) -> np.ndarray:
    ad, bd = _plant(T)
    x = np.zeros(2)
    out = []
    for k in range(n):
        est = obs.correct(x[0] / 1000.0)
        u = u_of_k(k)
        obs.predict(u)
        out.append(est.disturbance)
        x = ad @ x + bd * (u + d_of_k(k))
    return np.array(out)


def test_is_an_observer_and_starts_at_rest_with_zero_disturbance() -> None:
    obs = Imbdo(0.0, T)
    assert isinstance(obs, Observer)
    est = obs.correct(0.02)  # 20 mm away from the origin
    assert est.position == 0.02
    assert est.velocity == 0.0
    assert est.disturbance == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize('order', [2, 3])
def test_step_disturbance_is_recovered_with_the_q_filter_step_response(order: int) -> None:
    d0, k0, n = 0.05, 100, 3000  # 0.05 V step at 10 ms, 0.3 s run
    obs = Imbdo(0.0, T, ImbdoParams(q_order=order))
    d_hat = _run_open_loop(obs, lambda k: d0 if k >= k0 else 0.0, lambda k: 0.3, n)
    # Steady state: exact (both branches keep their DC gains).
    assert abs(d_hat[-1] - d0) < 1e-6 * d0
    # Transient: d̂ follows Q's continuous step response (one sample of timing slack).
    num, den = Imbdo(0.0, T, ImbdoParams(q_order=order)).q_filter()
    t = np.arange(n - k0) * T
    _, q_step = scipy.signal.step((num, den), T=t)
    err = np.abs(d_hat[k0:] - d0 * q_step)
    assert err.max() < 0.06 * d0
    # Settling (2 %) consistent with Q: measured against the continuous Q's own 2 % time.
    settle = t[np.nonzero(np.abs(d_hat[k0:] - d0) > 0.02 * d0)[0][-1]]
    settle_q = t[np.nonzero(np.abs(q_step - 1.0) > 0.02)[0][-1]]
    assert abs(settle - settle_q) <= 3 * T
    assert 0.005 < settle < 0.02  # ≈ 10.3 ms (n = 2) / 13.2 ms (n = 3) for Q at 90 Hz


def test_known_input_is_not_mistaken_for_a_disturbance() -> None:
    obs = Imbdo(0.0, T)
    d_hat = _run_open_loop(
        obs, lambda k: 0.0, lambda k: 0.5 * math.sin(2 * math.pi * 20 * k * T), 2000
    )
    assert np.max(np.abs(d_hat)) < 1e-2 * 0.5


def test_velocity_is_the_backward_difference_in_m_per_s() -> None:
    obs = Imbdo(0.0, T)
    obs.correct(0.001)
    obs.predict(0.0)
    est = obs.correct(0.001 + 2e-6)
    assert est.velocity == pytest.approx(2e-6 / T)


def test_parameters_are_checked() -> None:
    with pytest.raises(ParameterError, match='q_order'):
        Imbdo.from_parameters(0.0, T, {'q_order': 1})
    with pytest.raises(ParameterError, match='q_cutoff'):
        Imbdo.from_parameters(0.0, T, {'q_cutoff': -1.0})
    assert Imbdo.from_parameters(0.0, T, {}).sample_period == T
    with pytest.raises(RuntimeError):
        Imbdo(0.0, T).predict(0.0)
    obs = Imbdo(0.0, T)
    obs.correct(0.0)
    with pytest.raises(ValueError):
        obs.predict(math.nan)
