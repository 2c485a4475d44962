"""Beltrán 2013 claims checked on the offline simulator (equal to the distributed run:
test/test_lockstep_equality.py)."""

from __future__ import annotations

import numpy as np
import pytest
from mill_bringup.metrics import summarize
from mill_bringup.offline import simulate

from mill_bringup import scenario


def run(*overrides: str):
    scen = scenario.load('slotting')
    for text in overrides:
        scen.add_override(text)
    return simulate(scen)


def test_disturbance_compensation_beats_pd_by_100_times_on_every_axis():
    adrc = {m.axis: m for m in summarize(run('*_controller.controller=adrc'), skip=1.0)}
    pd = {m.axis: m for m in summarize(run('*_controller.controller=pd'), skip=1.0)}
    assert set(adrc) == set(pd) == {'x', 'y', 'z'}
    for axis in adrc:
        assert adrc[axis].rms_error * 100 <= pd[axis].rms_error, axis


@pytest.mark.parametrize('axis', [0, 1, 2])
def test_step_disturbance_estimated_within_5_percent_in_30_ms(axis):
    step_time = 1.0
    force = [0.0, 0.0, 0.0]
    force[axis] = 100.0
    rec = run(
        'plant.cutting_model=step',
        f'plant.step.force={force}',
        f'plant.step.start_time={step_time}',
        'trajectory.duration=1.2',
    )
    t = rec.t
    xi = rec['true_disturbance'][:, axis]
    xi_hat = rec['estimate_disturbance'][:, axis]
    # The step must be a real change of the disturbance, not lost in friction.
    before = xi[(t > step_time - 0.05) & (t < step_time)].mean()
    after = xi[(t > step_time) & (t < step_time + 0.2)].mean()
    assert abs(after - before) > 0.5  # 100 N on ~95 kg: ~1 m/s^2
    window = (t >= step_time + 0.030) & (t <= step_time + 0.2)
    rel = np.abs(xi_hat[window] - xi[window]) / np.abs(xi[window])
    assert rel.max() <= 0.05
