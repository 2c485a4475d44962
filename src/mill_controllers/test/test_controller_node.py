"""The axis controller node in this process: what a run-time parameter change does to it.

A change whose law cannot be built (issue 37: gpi.omega_n=1e300 overflowed and the node
died on the next `controller=gpi`) is refused with one line and the law that runs goes on,
also when the change is of a law that does not run; a trip is cleared by ~/reset_trip
alone, not by a write of following_error_limit (issue 34).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from mill_common.in_process import node_factory, set_one


@pytest.fixture
def controller(monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[..., Any]]:
    """controller(*ros_args) -> a AxisControllerNode `x_controller` in a context of its own."""
    from mill_controllers.axis_controller_node import AxisControllerNode

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(150 + os.getpid() % 10))
    with node_factory(AxisControllerNode, 'x_controller') as make:
        yield make


def refused(node: Any, name: str, value: Any) -> str:
    """Set it, expecting a refusal that leaves values, parameter and law as they were; the
    one-line reason."""
    law, values = node.loop.law, dict(node.params.values)
    result = set_one(node, name, value)
    assert not result.successful, f'{name}={value!r} was accepted'
    assert '\n' not in result.reason and result.reason
    assert node.loop.law is law and node.params.values == values
    assert node.get_parameter(name).value == values[name]
    return str(result.reason)


def command_at_rest(node: Any) -> float:
    """What the running law commands on an axis at rest, 1 mm behind its reference."""
    from mill_common.signals import AxisReference, ControlInputs, Estimate

    rest = ControlInputs(0.0, 0.0, AxisReference(1e-3, 0.0, 0.0), Estimate(0.0, 0.0, 0.0))
    return float(node.loop.law.compute(rest))


@pytest.mark.parametrize(
    ('name', 'value', 'why'),
    [
        ('gpi.omega_n', 1e300, 'OverflowError'),
        ('gpi.zeta', 1e300, 'OverflowError'),
        ('gpi.damping_rate', 1e300, 'LinAlgError: Singular matrix'),
        ('sliding_gpi.omega_n', 1e300, 'OverflowError'),
        ('sliding_gpi.zeta', 1e300, 'OverflowError'),
        ('sliding_gpi.damping_rate', 1e300, 'LinAlgError: Singular matrix'),
        ('pd.omega_c', 1e300, 'commands nan'),  # ω_c² is inf: the command is not finite
    ],
)
def test_a_gain_its_law_cannot_be_built_with_is_refused_running_or_not(
    controller, name: str, value: float, why: str
) -> None:
    law = name.split('.')[0]
    # Not the running law (adrc runs; pd.* belongs to it too: take gpi then).
    node = controller('-p', 'controller:=gpi' if law == 'pd' else 'controller:=adrc')
    reason = refused(node, name, value)
    assert reason.startswith(f'{name}={value!r}: ') and why in reason, reason
    # The running law.
    running = 'adrc' if law == 'pd' else law
    assert set_one(node, 'controller', running).successful
    before = command_at_rest(node)
    reason = refused(node, name, value)
    assert why in reason and '(not the running law)' not in reason, reason
    assert command_at_rest(node) == before  # the same law, with its gains, runs on
    assert set_one(node, 'blend_time', 0.02).successful  # and the node takes changes


def test_tiny_gains_build_a_law_that_runs(controller) -> None:
    # 1e-300 passes each check and builds finite (if useless) gains: accepted, and the
    # law computes a finite command.
    node = controller()
    assert set_one(node, 'gpi.omega_n', 1e-300).successful
    assert set_one(node, 'sliding_gpi.omega_n', 1e-300).successful
    for law in ('gpi', 'sliding_gpi'):
        assert set_one(node, 'controller', law).successful
        assert type(node.loop.law).__name__.lower().startswith(law.replace('_', ''))
        u = command_at_rest(node)
        assert u == u and abs(u) <= node.loop.law.torque_limit  # finite, within the limit


def test_a_bad_gain_given_at_start_up_ends_the_start_up_in_one_line(controller) -> None:
    # Issue 37: every law given other gains than its defaults is built at start-up, the
    # running one or not, so that no later switch to it can fail on them.
    from mill_common.ros_params import CoresNotBuilt

    overflow = "OverflowError: (34, 'Numerical result out of range')"
    with pytest.raises(CoresNotBuilt) as info:
        controller('-p', 'gpi.omega_n:=1e300')
    assert str(info.value) == f'gpi.omega_n=1e+300: gpi (not the running law): {overflow}'
    with pytest.raises(CoresNotBuilt) as info:
        controller('-p', 'controller:=gpi', '-p', 'gpi.omega_n:=1e300')
    assert str(info.value) == f"controller='gpi', gpi.omega_n=1e+300: {overflow}"
    node = controller('-p', 'gpi.omega_n:=100.0')  # a gain gpi builds with: it starts
    assert set_one(node, 'controller', 'gpi').successful


def test_a_trip_is_cleared_by_reset_trip_alone(controller) -> None:
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from std_srvs.srv import Trigger

    node = controller('-p', 'following_error_limit:=0.001')
    trip = node.loop.trip
    assert trip.command(0.25, 2e-3, 1.0) != trip.command(0.25, 2e-3, 1.0)  # NaN: braked
    for limit in (0.001, 0.01, float('inf')):  # the value it has, a larger one, none
        assert set_one(node, 'following_error_limit', limit).successful
        assert trip.limit == limit and trip.tripped, limit
    assert set_one(node, 'controller', 'pd').successful and trip.tripped

    probe = Node('operator', context=node.context)
    executor = SingleThreadedExecutor(context=node.context)
    for n in (node, probe):
        executor.add_node(n)
    try:
        client = probe.create_client(Trigger, '/x_controller/reset_trip')
        assert client.wait_for_service(timeout_sec=10)
        answers = []
        for _ in range(2):
            future = client.call_async(Trigger.Request())
            executor.spin_until_future_complete(future, timeout_sec=10)
            answers.append(future.result().message)
    finally:
        executor.shutdown()
        probe.destroy_node()
    assert answers == ['trip cleared', 'no trip to clear']
    assert not trip.tripped and trip.command(0.3, 1.0, 2.0) == 2.0  # limit inf: no trip
