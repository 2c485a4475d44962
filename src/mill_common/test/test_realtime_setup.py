"""Real-time scheduling as a deployment setting: which setting a process takes, and that
applying it says what was done or refused."""

from __future__ import annotations

import os
import subprocess
import sys

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


def test_a_listener_runs_below_the_graph_and_what_it_starts_runs_normally() -> None:
    assert realtime_setup.listener_priority(80) == 80 - realtime_setup.LISTENER_BELOW
    assert realtime_setup.listener_priority(3) == 1  # never off, never above the graph
    # in a process of its own, so that pytest stays on the normal scheduler
    script = (
        'import os, subprocess, sys\n'
        'from mill_common.realtime_setup import listen_at\n'
        'refused = listen_at(7)\n'
        'child = subprocess.run([sys.executable, "-c", "import os; '
        'print(os.sched_getscheduler(0))"], capture_output=True, text=True)\n'
        'print(os.sched_getscheduler(0), os.sched_getparam(0).sched_priority,'
        ' child.stdout.strip(), refused)\n'
    )
    out = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    policy, priority, child, refused = out.stdout.strip().split(maxsplit=3)
    if refused != '[]':  # no rtprio limit here: said in one line, nothing changed
        assert 'listener priority 7' in refused and int(policy) == os.SCHED_OTHER
        return
    assert int(policy) & ~os.SCHED_RESET_ON_FORK == os.SCHED_FIFO and int(priority) == 7
    assert int(child) == os.SCHED_OTHER  # the node processes it starts take their own
