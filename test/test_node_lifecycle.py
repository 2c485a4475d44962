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
