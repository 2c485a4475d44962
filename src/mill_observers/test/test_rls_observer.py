"""The rls observer identifies a known first-order velocity loop from position and command."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mill_common.parameters import ParameterError
from mill_common.signals import FopdtEstimate
from mill_observers.registry import make_observer

T = 0.25e-3
GAIN, TAU = 29.83, 0.05  # (m/s)/V and s: a Hatwesh-like velocity loop


@pytest.mark.parametrize('load', [0.0, 0.0437])
def test_converges_to_the_plants_gain_and_time_constant(load: float) -> None:
    """load: a constant load worth that many volts (0.0437 V: the 0.955 N·m of
    config/hatwesh_velocity.yaml over K_a K_t), seen by the load term (on by default)."""
    obs = make_observer('rls', 0.0, T, {'forgetting': 0.9999})
    a = math.exp(-T / TAU)
    rng = np.random.default_rng(3)
    u_seq = np.repeat(rng.choice([-0.01, 0.01], size=400), 25)  # PRBS, 6.25 ms steps
    x, v = 0.0, 0.0
    for u in u_seq:
        est = obs.correct(x)
        obs.predict(float(u))
        # exact ZOH sampling of τ v' = −v + K u, and x' = v
        v_next = a * v + GAIN * (1 - a) * (u - load)
        x += TAU * (v - v_next) + GAIN * (u - load) * T  # ∫ v dt over the sample
        v = v_next
    status = obs.status()
    assert status['gain'] == pytest.approx(GAIN, rel=0.01)
    assert status['time_constant'] == pytest.approx(TAU, rel=0.01)
    assert status['load'] == pytest.approx(load, abs=5e-4)  # measured 0.04347
    assert est.disturbance == 0.0
    # What the controller node reads back from observer_state is the offline model, exactly.
    assert FopdtEstimate.from_status(status) == obs.model_estimate()


def test_bad_forgetting_is_refused() -> None:
    with pytest.raises(ParameterError, match=r'rls\.forgetting'):
        make_observer('rls', 0.0, T, {'forgetting': 1.5})
