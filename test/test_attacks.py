"""Issue 37's attacks on a running job, each beside a short lockstep slotting run.

- a second copy of x_controller (a node of this test with the controller's name, started
  once the job steps, answering each x state with 10 N·m): the drive refuses both claimants
  and names them; x moves no further from its path than in the clean run;
- a ratchet: a node answering each x state it hears with a state in the plant's name
  stamped one period ahead: dropped by its publisher GID, named, and the job completes as
  the offline simulator computes it (no deadlock);
- parameter sequences against the running x_controller (`gpi.omega_n=1e300` then
  `controller=gpi`, the same with sliding_gpi) through its parameter services: each bad
  set refused with one line, the node alive, the job finished.

The clean figures are the offline simulator's (the same scenario, duration and metrics
window, no attacker): what the real graph alone makes.
"""

from __future__ import annotations

import argparse
import json
import re
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from test.conftest import EXTENDED, ParameterClient, ros_node, start_scenario  # noqa: F401

# Each attacker races a 2 s job (it must hear the job's states while the job runs): alone on
# the machine (scripts/test.sh, serial), so that the job does not end before it has spoken.
# With 1 s, the ratchet once answered 94 states in a CI run: it joins the running graph,
# and a joining participant holds the graph up and is matched late (docs/performance.md, "A
# participant joining the domain holds the graph up").
pytestmark = pytest.mark.serial

DURATION = '2'
SAMPLES = 2001  # t = 0 .. DURATION at 1 kHz, the start included
PERIOD_NS = 1_000_000  # slotting's sample period (1 kHz)
MARK = 12345.0  # the effort in the ratchet's states: it answers the plant's only


def clean_max_error(axis: str) -> float:
    """max |e| of `axis` [m] over the whole clean job (the offline simulator)."""
    from mill_bringup.cli import add_scenario_arguments, load_scenario
    from mill_bringup.jobs.base import simulate
    from mill_bringup.jobs.registry import job_for

    parser = argparse.ArgumentParser()
    add_scenario_arguments(parser)
    args = parser.parse_args(['slotting', '--duration', DURATION, '--skip', '0'])
    _scen, runs = load_scenario(args)
    (variant,) = runs.values()
    job = job_for(variant)
    metrics = job.summary(simulate(job), 0.0).to_json()['metrics']
    return next(m['max_error'] for m in metrics if m['axis'] == axis)


def max_error(summary: dict[str, Any], axis: str) -> float:
    return next(m['max_error'] for m in summary['metrics'] if m['axis'] == axis)


@contextmanager
def spun(make: Callable[[Any], None]) -> Iterator[threading.Event]:
    """A thread spinning a context of this process's own; `make(context)` is called in it
    once the event it yields is set (the attacker appears then), and it returns the node
    it made, which is spun until the block ends."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    context = rclpy.Context()
    rclpy.init(args=[], context=context)
    executor = SingleThreadedExecutor(context=context)
    go, stop = threading.Event(), threading.Event()
    nodes: list[Any] = []

    def spin() -> None:
        go.wait()
        if stop.is_set():
            return
        nodes.append(make(context))
        executor.add_node(nodes[-1])
        while not stop.is_set():
            executor.spin_once(timeout_sec=0.05)

    thread = threading.Thread(target=spin, daemon=True)
    thread.start()
    try:
        yield go
    finally:
        stop.set()
        go.set()
        thread.join(timeout=5)
        executor.shutdown()
        for node in nodes:
            node.destroy_node()
        rclpy.try_shutdown(context=context)


def run_job(ros_env, out: Path, go: threading.Event, *more: str) -> tuple[int, str, dict]:
    """The slotting job (processes, compared offline); `go` set at its first progress line
    (the job has stepped: every node runs). Returns (exit code, output, summary)."""
    proc = start_scenario(
        ros_env,
        *('slotting', '--layout', 'processes', '--duration', DURATION, '--skip', '0'),
        *('--compare-offline', '--output', str(out), *more),
    )
    assert proc.stderr is not None and proc.stdout is not None
    lines = []
    for line in proc.stderr:
        lines.append(line)
        if re.match(rf'\s*[0-9.]+ / {float(DURATION):.2f} s', line):
            go.set()
    text = proc.stdout.read() + ''.join(lines)
    code = proc.wait(timeout=120)
    assert (out / 'summary.json').exists(), f'no summary (exit {code}):\n{text[-3000:]}'
    return code, text, json.loads((out / 'summary.json').read_text())


def answering(name: str, topic: str, reply: Callable[[int], bytes], sent: list[int]) -> Callable:
    """make(context) of a node `name` answering each x state with reply(its stamp) on topic."""

    def make(context: Any) -> Any:
        from mill_common.codec import decode_joint_state
        from mill_common.ros import DATA_QOS, from_stamp, take_serialized
        from rclpy.node import Node
        from sensor_msgs.msg import JointState

        node = Node(name, context=context)
        pub = node.create_publisher(JointState, topic, DATA_QOS)

        def answer(msg: Any) -> None:
            if list(msg.effort) != [MARK]:  # not its own (the ratchet hears itself)
                pub.publish(reply(from_stamp(msg.header.stamp)))
                sent[0] += 1

        take_serialized(
            node, JointState, 'mill/x/state', decode_joint_state, answer, DATA_QOS, print
        )
        return node

    return make


@pytest.mark.system
# Quarantined in the extended suite: 1 run in 3 reports no `braked` event although the drive
# took both claimants' commands as brake requests (the contest seen before the job's first
# step); open in the closing note of 5 December 2026.
@EXTENDED
def test_a_second_copy_of_the_x_controller_is_refused_and_named(ros_env, tmp_path) -> None:
    from mill_common.ros import joint_state_bytes

    sent = [0]
    command = lambda ns: joint_state_bytes(ns, ('x',), effort=(10.0,), sender='x_controller')  # noqa: E731
    with spun(answering('x_controller', 'mill/x/joint_command', command, sent)) as go:
        code, text, summary = run_job(ros_env, tmp_path / 'run', go)
    assert sent[0] > 100, text[-3000:]  # it spoke all along the job, beside the owner
    # The drive names both claimants, each by its GID, in one line of the report.
    contests = [f for f in summary['foreign_publishers'] if '(plant)' in f and 'contested' in f]
    assert len(contests) == 1, (summary['foreign_publishers'], text[-3000:])
    gids = set(re.findall(r'/x_controller \(gid ([0-9a-f.]+)\)', contests[0]))
    assert len(gids) == 2, contests
    assert f'ERROR: {contests[0]}' in text.splitlines(), text[-3000:]
    # ... and refuses both: x braked (the drive took their commands as brake requests)
    # and moved no further from its path than in the clean job.
    (braked,) = summary['events']
    assert (braked['axis'], braked['kind'], braked['source']) == ('x', 'braked', 'plant')
    clean = clean_max_error('x')
    assert max_error(summary, 'x') <= clean, (max_error(summary, 'x'), clean, text[-3000:])
    # The job ran to its end; in lockstep a brake is not a machine's failure, but the
    # runner's record lacks the refused commands: exit 3.
    assert summary['samples'] == SAMPLES and summary['error'] is None, text[-3000:]
    left_out = 'left out .* messages on mill/x/joint_command from /x_controller'
    assert any(re.search(left_out, p) for p in summary['problems']), summary['problems']
    assert code == 3 == summary['exit_code'], text[-3000:]
    assert 'Traceback' not in text


@pytest.mark.system
def test_a_ratchet_of_states_in_the_plants_name_is_dropped_and_named(ros_env, tmp_path) -> None:
    from mill_common.ros import joint_state_bytes

    sent = [0]

    def ahead(ns: int) -> bytes:  # the state of the next step, one period ahead
        return joint_state_bytes(ns + PERIOD_NS, ('x',), (-0.075,), (0.0,), (MARK,), sender='plant')

    with spun(answering('ratchet', 'mill/x/state', ahead, sent)) as go:
        code, text, summary = run_job(ros_env, tmp_path / 'run', go)
    assert sent[0] > 100, text[-3000:]
    # The job completed, as the offline simulator computes it without the ratchet.
    assert summary['samples'] == SAMPLES and summary['events'] == [], text[-3000:]
    assert summary['offline_max_difference'] == 0.0, text[-3000:]
    named = ' '.join(summary['foreign_publishers'])
    assert 'ratchet' in named and 'mill/x/state' in named, summary['foreign_publishers']
    assert code == 3 == summary['exit_code'], text[-3000:]  # a good job, its record not intact
    assert 'Traceback' not in text


@pytest.mark.system
def test_bad_parameter_sequences_at_run_time_are_refused_and_the_job_finishes(
    ros_env, tmp_path
) -> None:
    # Issue 37 item 4: gpi.omega_n=1e300 was accepted, then controller=gpi got no reply and
    # x_controller died with OverflowError (the same with sliding_gpi).
    results: list[tuple[str, Any]] = []
    alive: list[str] = []

    def attack(context: Any) -> Any:
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node

        node = Node('operator', context=context)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        client = ParameterClient(node, executor, 'x_controller')
        for law in ('sliding_gpi', 'gpi'):
            for name, value in ((f'{law}.omega_n', 1e300), ('controller', law)):
                results.append((f'{name}={value}', client.set(name, value)))
        # back to the scenario's law: sliding_gpi and gpi at slotting's gains are not tuned
        # for it (offline, from the start, they trip y and z within 0.07 s)
        results.append(('controller=adrc', client.set('controller', 'adrc')))
        alive.append(client.get('controller')['controller'])
        executor.remove_node(node)
        return node

    with spun(attack) as go:
        code, text, summary = run_job(ros_env, tmp_path / 'run', go)
    assert len(results) == 5, (results, text[-3000:])
    for change, result in results[0:4:2]:  # each gain the law cannot be built with: refused
        assert not result.successful, change
        assert result.reason.count('\n') == 0 and 'OverflowError' in result.reason, result.reason
    # ... so the switch to the law (at its own gains) is taken, and the node runs on it
    assert all(result.successful for _change, result in results[1::2]), results
    assert alive == ['adrc']
    # and the job finished. The laws it ran on for a few steps may trip x (a switch's
    # transient, the law's own doing): then the one true line of it is x_controller's
    # following-error trip, and the drive's brake on its request; nothing else happened.
    assert summary['samples'] == SAMPLES and summary['error'] is None, text[-3000:]
    happened = {(e['axis'], e['kind'], e['source']) for e in summary['events']}
    assert happened <= {('x', 'trip', 'x_controller'), ('x', 'braked', 'plant')}, happened
    assert code == 0 == summary['exit_code'], text[-3000:]  # a lockstep trip is the law's
    assert 'Traceback' not in text
