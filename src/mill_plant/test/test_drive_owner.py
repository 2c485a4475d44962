"""The drive obeys its axis's owner as the graph identifies it (issue 37 items 1–2): the
real plant node on the wall clock, real rclpy nodes in a private domain answering its
states. A rogue writing the owner's name in frame_id drives nothing; a second node with
the owner's name gets both refused, named, and the axis braked."""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import pytest
from mill_common.in_process import Graph


class Machine(Graph):
    """The plant node on the wall clock, and the nodes answering its states."""

    drive: Any = None

    def answering(self, name: str, effort: float) -> None:
        """A node `name` answering each x state of the drive with `effort`, its frame_id
        'x_controller' whoever it is."""
        from mill_common.codec import decode_joint_state
        from mill_common.ros import DATA_QOS, from_stamp, joint_state_bytes, take_serialized
        from sensor_msgs.msg import JointState

        node = self.node(name)
        pub = node.create_publisher(JointState, 'mill/x/joint_command', DATA_QOS)

        def answer(msg: Any) -> None:
            ns = from_stamp(msg.header.stamp)
            pub.publish(joint_state_bytes(ns, ('x',), effort=(effort,), sender='x_controller'))

        take_serialized(node, JointState, 'mill/x/state', decode_joint_state, answer, 10, print)


@pytest.fixture
def machine() -> Iterator[Machine]:
    from mill_plant.plant_node import make_node
    from rclpy.parameter import Parameter

    with Machine(160, period=0.02) as machine:
        realtime = [Parameter('timing', value='realtime')]
        machine.drive = machine.add(
            make_node(context=machine.context, parameter_overrides=realtime)
        )
        yield machine


def test_a_rogue_with_the_owners_frame_id_drives_nothing_and_is_named(machine) -> None:
    drive = machine.drive
    machine.answering('rogue', 10.0)  # the attack of issue 37 item 1: 10 N·m as x_controller
    own = drive.ownership
    assert machine.spin_until(lambda: own.foreign_messages >= 50)
    x = drive.table.by_axis['x']
    assert x.stamp == -1 and math.isnan(x.value)  # not one command taken: held braked
    assert list(own.foreign) == ['mill/x/joint_command']
    named = own.foreign['mill/x/joint_command']
    # by a message it sent, and maybe also by the graph's look once a second ('rogue')
    assert "/rogue (frame_id 'x_controller')" in named and named <= {
        "/rogue (frame_id 'x_controller')",
        'rogue',
    }
    # The owner, answering beside it, is obeyed.
    machine.answering('x_controller', 0.25)
    assert machine.spin_until(lambda: x.value == 0.25)
    counted = own.foreign_messages
    machine.spin(0.3)
    assert x.value == 0.25 and own.foreign_messages > counted  # the rogue goes on, unheard


def test_a_second_node_with_the_owners_name_gets_both_refused_and_the_axis_braked(
    machine,
) -> None:
    drive = machine.drive
    x = drive.table.by_axis['x']
    machine.answering('x_controller', 0.25)
    assert machine.spin_until(lambda: x.value == 0.25)
    machine.answering('x_controller', 0.5)  # issue 37 item 2: a second x_controller
    own = drive.ownership
    assert machine.spin_until(lambda: 'mill/x/joint_command' in own.contests)
    machine.spin(0.3)
    owner, claimants = own.contests['mill/x/joint_command']
    assert owner == 'x_controller' and len(claimants) == 2
    assert all(c.startswith('/x_controller (gid ') for c in claimants)
    assert claimants[0] != claimants[1]
    assert math.isnan(x.value)  # neither drives it: each command is taken as a brake
    assert drive.intake.invalid_commands['x'] > 0
    status = own.status(drive.diagnostics)
    assert status is not None
    values = {kv.key: kv.value for kv in status.values}
    assert values['contested'] == f'mill/x/joint_command: x_controller: {"; ".join(claimants)}'
