"""Nodes end cleanly on signals, also on the double SIGINT of Ctrl-C under `ros2 launch`
(the terminal's and the one launch forwards)."""

from __future__ import annotations

import signal
import time

import pytest

from test.conftest import ros_node, wait_until


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

        assert wait_until(stepping, 300), 'the job never started'
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
