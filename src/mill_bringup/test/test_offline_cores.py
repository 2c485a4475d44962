"""The offline simulator's axis cores: a controller that designs with the observer's model
must be paired with an observer that estimates one."""

from __future__ import annotations

import numpy as np
import pytest
from mill_bringup.axis_simulation import build_axis_loops
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.registry import job_for
from mill_bringup.offline import CoreTimes

from mill_bringup import scenario


def test_a_model_hungry_controller_without_the_rls_observer_is_refused() -> None:
    scen = scenario.load('hatwesh').variant('adaptive_pi_rls')
    controllers, observers = build_axis_loops(job_for(scen).config)  # rls observer: fits
    assert controllers[0].law.needs_model and observers[0].observer.PROVIDES_MODEL
    scen.add_override('x_observer.observer=dfo')
    with pytest.raises(scenario.ScenarioError, match=r'x_observer \(observer dfo\).*rls'):
        job_for(scen)


def test_the_rls_observer_model_gives_the_same_run_as_the_own_estimator() -> None:
    runs = {}
    for name in ('adaptive_pi', 'adaptive_pi_rls'):
        scen = scenario.load('hatwesh').variant(name)
        scen.add_override('trajectory.duration=0.3')
        runs[name] = simulate(job_for(scen))
    a, b = runs['adaptive_pi'].signals, runs['adaptive_pi_rls'].signals
    assert len(runs['adaptive_pi'].t) == 1201
    for signal in ('torque', 'position'):  # the x axis; y and z are not simulated (nan)
        assert np.array_equal(a[signal][:, 0], b[signal][:, 0])
    assert np.ptp(a['position'][:, 0]) > 1e-3  # a real move (the gains adapt from 0.1 s on)


def test_core_times_count_every_call_and_change_nothing() -> None:
    scen = scenario.load('slotting')
    scen.add_override('trajectory.duration=0.05')
    times = CoreTimes()
    timed = simulate(job_for(scen), times=times)
    plain = simulate(job_for(scen))
    n = len(timed.t)
    assert n == 51
    assert times.calls == {'trajectory': n, 'observer': 3 * n, 'controller': 3 * n, 'plant': n}
    assert all(us > 0.0 for us in times.per_call_us().values())
    assert np.array_equal(timed.signals['position'], plain.signals['position'])
