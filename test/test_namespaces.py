"""Two machines in one domain: each graph under its own namespace, at the same time.

Both runs share ROS_DOMAIN_ID; each puts every topic under its namespace and keeps its
simulation clock there (--private-clock; two plants on one /clock are refused, the second
test), while /diagnostics stays global. Each run must equal its own offline simulation
sample for sample: the two machines run different laws (adrc and pd), so a state, estimate
or command of the other machine taken by an observer or a controller would show. pd trips
on following error on every axis (as offline): machine_a must see none of those trips.
Two clean machines side by side are quiet (no WARN or ERROR line anywhere), and their
statuses on the shared /diagnostics carry their namespace in the name as well as in
hardware_id, so that a tool keyed on names never merges them.
"""

from __future__ import annotations

import json
import re
import subprocess
import time
from pathlib import Path

import pytest
from mill_analysis.bag_run import read_run
from mill_bag.reader import open_bag

from mill_common import topics
from test.conftest import start_scenario

DURATION = '0.3'
SAMPLES = 301  # t = 0 .. 0.3 s at 1 kHz


def _runner(ros_env: dict[str, str], out: Path, *args: str) -> subprocess.Popen[str]:
    return start_scenario(
        ros_env,
        *('slotting', '--duration', DURATION, '--compare-offline', '--quiet'),
        *('--output', str(out), *args),
    )


@pytest.mark.system
def test_two_machines_in_one_domain_each_equal_their_offline_run(ros_env, tmp_path):
    runs = {
        # --view: machine_view beside machine_a's graph, in its namespace (its URDF in the bag)
        'machine_a': ('--controller', 'adrc', '--record', str(tmp_path / 'a_bag'), '--view'),
        'machine_b': ('--controller', 'pd'),  # trips at 1 mm on every axis, as offline
    }
    procs = {
        name: _runner(ros_env, tmp_path / name, '--namespace', name, '--private-clock', *args)
        for name, args in runs.items()
    }
    for name, proc in procs.items():
        _out, err = proc.communicate(timeout=900)
        assert proc.returncode == 0, f'{name}: {err[-3000:]}'
    for name in runs:
        summary = json.loads((tmp_path / name / 'summary.json').read_text())
        assert summary['samples'] == SAMPLES
        assert summary['missing_samples'] == {}, name
        # Every sample of every axis: |e_distributed - e_offline| <= 1e-9 m (the equality
        # of the default-namespace run, test_lockstep_equality).
        assert summary['offline_max_difference'] <= 1e-9, name
        trips = [p for p in summary['problems'] if 'following-error trip' in p]
        if name == 'machine_b':  # its own trips, one per axis, reported by its controllers
            senders = {p.split(':')[0] for p in trips}
            assert senders >= {f'machine_b/{a}_controller' for a in 'xyz'}, trips
        else:  # nothing of the other machine's diagnostics
            assert trips == [], summary['problems']
            assert not [p for p in summary['problems'] if 'braked' in p], summary['problems']
    # The bag of machine_a holds its own topics under its namespace, none of machine_b's,
    # and report reads it as the run it is.
    bag = open_bag(tmp_path / 'a_bag')
    names = {name for name, *_ in bag.read()}
    assert topics.qualify(topics.state('x'), 'machine_a') in names
    assert '/machine_a/clock' in names and topics.DIAGNOSTICS in names
    assert topics.qualify(topics.ROBOT_DESCRIPTION, 'machine_a') in names  # --view
    assert not [n for n in names if n.startswith('/machine_b') or n.startswith('/mill/')]
    run = read_run(tmp_path / 'a_bag')
    assert run.n >= SAMPLES and run.missing == {}


@pytest.mark.system
def test_a_second_clock_in_the_domain_is_refused(ros_env, tmp_path):
    from rosgraph_msgs.msg import Clock

    from test.conftest import ros_node

    with ros_node('other_simulation') as (node, executor):
        pub = node.create_publisher(Clock, topics.CLOCK, 10)
        proc = _runner(ros_env, tmp_path / 'run')
        deadline = time.monotonic() + 600
        while proc.poll() is None and time.monotonic() < deadline:
            pub.publish(Clock())
            executor.spin_once(timeout_sec=0.1)
        _out, err = proc.communicate(timeout=60)
    lines = [line for line in err.splitlines() if line.startswith('run_scenario:')]
    assert proc.returncode == 1, err[-3000:]
    assert len(lines) == 1, err[-3000:]
    # The check runs once a second from the start: it may see the other clock before or
    # after this run's own plant publishes, but it always counts exactly one too many.
    counts = re.search(r'/clock has (\d+) publishers .* this run has (\d+):', lines[0])
    assert counts is not None, lines[0]
    assert int(counts[1]) == int(counts[2]) + 1, lines[0]
    assert 'another simulation shares the domain' in lines[0]


@pytest.mark.system
@pytest.mark.serial  # two graphs with no WARN line: alone on the machine (scripts/test.sh)
def test_two_clean_machines_are_quiet_and_their_statuses_never_merge(ros_env, tmp_path):
    from diagnostic_msgs.msg import DiagnosticArray

    from test.conftest import ros_node

    heard: dict[str, set[str]] = {}  # hardware_id -> status names

    def on_statuses(msg: DiagnosticArray) -> None:
        for s in msg.status:
            heard.setdefault(s.hardware_id, set()).add(s.name)

    machines = ('machine_a', 'machine_b')
    with ros_node('status_listener') as (node, executor):
        node.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, on_statuses, 100)
        procs = {
            name: _runner(ros_env, tmp_path / name, '--namespace', name, '--private-clock')
            for name in machines
        }
        while any(p.poll() is None for p in procs.values()):
            executor.spin_once(timeout_sec=0.1)
        for _ in range(10):  # what is still queued
            executor.spin_once(timeout_sec=0.05)
    errs = {name: proc.communicate(timeout=60)[1] for name, proc in procs.items()}
    for name, proc in procs.items():
        assert proc.returncode == 0, f'{name}: {errs[name][-3000:]}'
        summary = json.loads((tmp_path / name / 'summary.json').read_text())
        assert summary['problems'] == [], (name, summary['problems'])
        logs = sorted((tmp_path / name / 'logs').glob('*.log'))
        assert len(logs) >= 8, logs
        for log in logs:
            noisy = [
                ln for ln in log.read_text().splitlines() if ln.startswith(('[WARN]', '[ERROR]'))
            ]
            assert noisy == [], f'{name} {log.name}: {noisy}'
        noisy = [ln for ln in errs[name].splitlines() if '[WARN]' in ln or '[ERROR]' in ln]
        assert noisy == [], f'{name}: {noisy}'
    # Each machine's statuses are named after it (the trajectory's job, each controller's
    # inputs, ...), and no name is both machines'.
    names = {name: heard.get(topics.machine_id(name), set()) for name in machines}
    for name in machines:
        assert names[name], f'no status of {name} heard: {sorted(heard)}'
        parsed = [topics.parse_status_name(n) for n in names[name]]
        assert {p.namespace for p in parsed} == {topics.machine_id(name)}, names[name]
        assert topics.status_name('trajectory', topics.JOB_STATUS, name) in names[name]
    assert names['machine_a'].isdisjoint(names['machine_b'])
    keys = [{topics.status_key(n) for n in names[m]} for m in machines]
    assert keys[0] & keys[1], 'the two machines should report the same node parts'
