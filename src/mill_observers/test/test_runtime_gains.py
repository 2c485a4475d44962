"""A run-time change of the Maharof observers' nominal model or Q filter rebuilds the
observer, as any other gain change does (an observer node on rclpy, in this process).

imbdo.plant_gain, imbdo.q_cutoff (and those of imbdo_dfo, and dfo.plant_gain) were once
read-only by accident: a check had been passed where the read-only flag belongs.
"""

from __future__ import annotations

import os
from collections.abc import Iterator

import pytest
from mill_observers.registry import make_observer

T = 1e-3  # the node's default sample_period

CHANGES = [
    ('imbdo', 'plant_gain', 70000.0),
    ('imbdo', 'q_cutoff', 60.0),
    ('dfo', 'plant_gain', 70000.0),
    ('imbdo_dfo', 'plant_gain', 70000.0),
    ('imbdo_dfo', 'q_cutoff', 60.0),
]


@pytest.fixture
def observer_node(monkeypatch: pytest.MonkeyPatch) -> Iterator:
    """observer_node(observer) -> an ObserverNode running that observer, in its own context."""
    import rclpy
    from mill_observers.observer_node import ObserverNode
    from rclpy.parameter import Parameter

    from mill_common import ros_params

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(101 + os.getpid() % 19))
    monkeypatch.setattr(ros_params, 'command_line', ['test'])
    made = []

    def make(observer: str) -> ObserverNode:
        context = rclpy.Context()
        rclpy.init(args=['test'], context=context)
        node = ObserverNode(
            context=context, parameter_overrides=[Parameter('observer', value=observer)]
        )
        made.append((node, context))
        return node

    yield make
    for node, context in made:
        node.destroy_node()
        rclpy.try_shutdown(context=context)


def _estimates(obs) -> list:  # type: ignore[no-untyped-def]
    out = [obs.correct(0.01)]
    for k in range(50):
        obs.predict(0.1 if k % 10 < 5 else -0.1)
        out.append(obs.correct(0.01 + 1e-6 * k))
    return out


@pytest.mark.parametrize(('observer', 'name', 'value'), CHANGES)
def test_a_run_time_change_rebuilds_the_observer(observer_node, observer, name, value) -> None:
    from rclpy.parameter import Parameter

    node = observer_node(observer)
    full = f'{observer}.{name}'
    assert not node.describe_parameter(full).read_only
    before = node._loop.observer
    assert node.set_parameters_atomically([Parameter(full, value=value)]).successful
    after = node._loop.observer
    assert after is not before
    assert node.get_parameter(full).value == value
    # the new observer is the one the new value builds, and not the old one
    wanted = _estimates(make_observer(observer, 0.0, T, {name: value}))
    assert _estimates(after) == wanted
    assert _estimates(make_observer(observer, 0.0, T, {})) != wanted
