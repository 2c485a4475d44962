"""Real-time scheduling as a deployment setting: which setting a process takes, and that
applying it says what was done or refused."""

from __future__ import annotations

import os

import pytest
from mill_common.node_params import realtime_specs
from mill_common.parameters import ParameterError, validate

from mill_common import realtime_setup


def test_the_process_takes_the_highest_priority_and_every_cpu_named() -> None:
    values = [
        {'realtime_priority': 0, 'cpu_affinity': []},
        {'realtime_priority': 70, 'cpu_affinity': [1]},
        {'realtime_priority': 50, 'cpu_affinity': [0, 1]},
        {'axis': 'x'},  # a node without the setting
    ]
    assert realtime_setup.wanted(values) == (70, [0, 1])
    assert realtime_setup.wanted([{'realtime_priority': 0, 'cpu_affinity': []}]) == (0, [])


def test_bad_settings_are_refused_by_name() -> None:
    specs = dict(realtime_specs())
    with pytest.raises(ParameterError, match='realtime_priority'):
        validate(specs['realtime_priority'], 99, 'realtime_priority')
    with pytest.raises(ParameterError, match='each CPU once'):
        validate(specs['cpu_affinity'], [0, 0], 'cpu_affinity')


def test_nothing_asked_nothing_done_and_an_affinity_is_applied() -> None:
    assert realtime_setup.apply(0, []) == ([], [])
    before = os.sched_getaffinity(0)
    cpu = min(before)
    try:
        done, refused = realtime_setup.apply(0, [cpu])
        assert done == [f'CPUs {cpu}'] and refused == []
        assert os.sched_getaffinity(0) == {cpu}
    finally:
        for tid in os.listdir('/proc/self/task'):
            os.sched_setaffinity(int(tid), before)
