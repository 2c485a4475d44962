"""Nodes end cleanly on signals, also on the double SIGINT of Ctrl-C under `ros2 launch`
(the terminal's and the one launch forwards), and at any moment of their start-up."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from test.conftest import SCENARIO, ros_node, wait_until


def wait_until_in_graph(name: str) -> None:
    """The node has started spinning (its signal handlers are installed by then)."""
    with ros_node('lifecycle_probe') as (probe, _executor):
        assert wait_until(lambda: name in probe.get_node_names(), 60), f'{name} never appeared'


NODES = [
    ('mill_controllers.axis_controller_node', 'x_controller'),
    ('mill_observers.observer_node', 'x_observer'),
    ('mill_trajectory.trajectory_node', 'trajectory'),
    ('mill_plant.plant_node', 'plant'),
]


@pytest.mark.system
@pytest.mark.parametrize(('module', 'name'), NODES, ids=[n for _, n in NODES])
def test_double_sigint_exits_cleanly(start_node, module, name) -> None:
    node = start_node(module, name)
    wait_until_in_graph(name)
    assert node.alive()
    node.proc.send_signal(signal.SIGINT)
    time.sleep(0.05)
    if node.alive():
        node.proc.send_signal(signal.SIGINT)
    code, _out, err = node.wait(timeout=30)
    assert code == 0, err
    assert 'Traceback' not in err and 'terminate' not in err, err


@pytest.mark.system
def test_sigterm_exits_cleanly(start_node) -> None:
    node = start_node('mill_controllers.axis_controller_node', 'x_controller')
    wait_until_in_graph('x_controller')
    node.proc.send_signal(signal.SIGTERM)
    code, _out, err = node.wait(timeout=30)
    assert code == 0, err
    assert 'Traceback' not in err, err


# ros2 launch escalates to SIGTERM when a process has not ended 5 s after its SIGINT
# (sigterm_timeout): the deadline comes from launch, not from a speed we measure.
LAUNCH_SIGTERM_TIMEOUT = 5.0


@pytest.mark.system
def test_ctrl_c_ends_a_running_graph_before_launch_escalates(start_node) -> None:
    from mill_common.ros import DATA_QOS
    from sensor_msgs.msg import JointState

    from mill_bringup import scenario
    from mill_common import topics

    scen = scenario.load('slotting')
    nodes = {n.name: start_node(n.kind.module, n.name) for n in scen.nodes}
    with ros_node('ctrl_c_probe') as (probe, executor):
        states: list[JointState] = []
        probe.create_subscription(JointState, topics.state('x'), states.append, DATA_QOS)

        def stepping() -> bool:
            executor.spin_once(timeout_sec=0.05)
            return len(states) > 50  # the lockstep job runs

        if not wait_until(stepping, 300):
            ends = {name: node.stop() for name, node in nodes.items()}
            lines = [f'{n}: exit {code}: {err[-600:]}' for n, (code, _out, err) in ends.items()]
            raise AssertionError('the job never started:\n' + '\n'.join(lines))
    t0 = time.monotonic()
    for node in nodes.values():  # the terminal's SIGINT, then the one launch forwards
        node.proc.send_signal(signal.SIGINT)
    time.sleep(0.05)
    for node in nodes.values():
        if node.alive():
            node.proc.send_signal(signal.SIGINT)
    ended: dict[str, float] = {}
    while len(ended) < len(nodes) and time.monotonic() - t0 < 30:
        for name, node in nodes.items():
            if name not in ended and not node.alive():
                ended[name] = time.monotonic() - t0
        time.sleep(0.01)
    late = {n: round(t, 2) for n, t in ended.items() if t > LAUNCH_SIGTERM_TIMEOUT}
    assert len(ended) == len(nodes) and not late, (ended, late)
    for name, node in nodes.items():
        code, _out, err = node.wait(timeout=5)
        assert code == 0, f'{name}: {err}'
        assert 'Traceback' not in err, f'{name}: {err}'


# -- a stop at any moment of the start-up ------------------------------------------------------
# Points after the process's first own line (s): during the imports, rclpy's init, the nodes'
# construction, discovery, the first steps; on a slower machine they fall earlier in the
# start-up. Before that line Python itself starts (about 40 ms here): a signal then ends the
# process by the signal, as for any Python program (docs/reliability.md).
START_UP_POINTS = (0.0, 0.05, 0.15, 0.4, 1.0, 2.5)
CLEAN = ('Traceback', 'Exception ignored', 'race condition', 'terminate called')
STOP_SIGNALS_MASK = (1 << (signal.SIGINT - 1)) | (1 << (signal.SIGTERM - 1))


def _console_script(name: str) -> str:
    """The executable `ros2 run` starts (the console script), not `python -m`."""
    return str(Path(sys.executable).with_name(name))


def _holds_stop_signals(pid: int) -> bool:
    """The process runs its own first line: SIGINT and SIGTERM blocked (mill_common.executable)."""
    try:
        status = Path(f'/proc/{pid}/status').read_text()
    except OSError:
        return False
    blocked = int(next(ln for ln in status.splitlines() if ln.startswith('SigBlk:')).split()[1], 16)
    return blocked & STOP_SIGNALS_MASK == STOP_SIGNALS_MASK


def _start_and_stop(
    cmd: list[str], env: dict[str, str], after: float, first: int
) -> tuple[int, str, float]:
    """Start cmd, send `first` `after` s after its first own line, then SIGTERM 50 ms later
    if it still runs (a user's second Ctrl-C, launch's escalation); (exit code, output, how
    long it took to end [s])."""
    proc = subprocess.Popen(
        cmd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )
    try:
        assert wait_until(lambda: _holds_stop_signals(proc.pid), 60, step=0.001), 'no start'
        time.sleep(after)
        t0 = time.monotonic()
        proc.send_signal(first)
        time.sleep(0.05)
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
        out = proc.communicate(timeout=60)[0]
        return proc.returncode, out, time.monotonic() - t0
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()


@pytest.mark.system
@pytest.mark.parametrize('after', START_UP_POINTS)
@pytest.mark.parametrize('first', [signal.SIGINT, signal.SIGTERM], ids=['SIGINT', 'SIGTERM'])
def test_a_node_stopped_at_any_moment_of_its_start_up_ends_quietly(
    ros_env, after: float, first: int
) -> None:
    code, out, took = _start_and_stop(
        [
            *(_console_script('axis_controller_node'), '--ros-args'),
            *('-r', '__node:=x_controller', '--params-file', str(SCENARIO)),
        ],
        ros_env,
        after,
        first,
    )
    assert code == 0, out
    assert not [c for c in CLEAN if c in out], out
    assert took < LAUNCH_SIGTERM_TIMEOUT, took


@pytest.mark.system
@pytest.mark.parametrize('after', START_UP_POINTS[::2])
def test_run_scenario_stopped_at_any_moment_of_its_start_up_ends_quietly(
    ros_env, tmp_path: Path, after: float
) -> None:
    run_dir = tmp_path / 'run'
    code, out, took = _start_and_stop(
        [_console_script('run_scenario'), 'slotting', '--duration', '2', '--output', str(run_dir)],
        ros_env,
        after,
        signal.SIGINT,
    )
    # A run the user stopped is not a finished one: 130, as a shell reports Ctrl-C.
    assert code == 130, out
    assert out.strip().splitlines()[-1] == 'run_scenario: interrupted', out
    assert not [c for c in CLEAN if c in out], out
    assert took < LAUNCH_SIGTERM_TIMEOUT, took
    for log in sorted((run_dir / 'logs').glob('*.log')):  # the nodes it had started
        text = log.read_text()
        assert not [c for c in CLEAN if c in text], f'{log.name}: {text}'
