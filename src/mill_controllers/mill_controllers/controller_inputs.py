"""Where each per-sample input of the axis controller comes from, and how it is read.

One entry per field of ControlInputs (but t): its message type and topic, the parameter
naming the node that must send it, and the function that takes its samples — (stamp,
value) pairs — out of a message, or says why the message is no use. A new per-step input
is one entry here and one field of ControlInputs.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from mill_common.checks import Rejected, axis_points, joint_values
from mill_common.codec import decode_joint_state, decode_joint_trajectory
from mill_common.ros import from_duration, from_stamp
from mill_common.signals import AxisReference, Estimate, FopdtEstimate
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from mill_common import topics

Samples = list[tuple[int, Any]]  # (stamp [ns], value) pairs read from one message


def _position(msg: JointState, axis: str) -> Samples | Rejected:
    got = joint_values(msg.name, {'position': msg.position}, axis, ('position',))
    return got if isinstance(got, Rejected) else [(from_stamp(msg.header.stamp), got[0])]


def _estimate(msg: JointState, axis: str) -> Samples | Rejected:
    arrays = {'position': msg.position, 'velocity': msg.velocity, 'effort': msg.effort}
    got = joint_values(msg.name, arrays, axis, ('position', 'velocity', 'effort'))
    return got if isinstance(got, Rejected) else [(from_stamp(msg.header.stamp), Estimate(*got))]


def _reference(msg: JointTrajectory, axis: str) -> Samples | Rejected:
    got = axis_points(msg.joint_names, msg.points, axis)
    if isinstance(got, Rejected):
        return got  # the whole message: a partial reference is no reference
    ns0 = from_stamp(msg.header.stamp)
    return [
        (ns0 + from_duration(p.time_from_start), AxisReference(*values))
        for p, values in zip(msg.points, got, strict=True)
    ]


def _model(msg: JointState, axis: str) -> Samples | Rejected:
    model = FopdtEstimate.from_status(dict(zip(msg.name, msg.position, strict=False)))
    if model is None:
        return []  # another observer's state: no model in it
    if not all(math.isfinite(v) for v in model.as_status().values()):
        return Rejected('non-finite model estimate')
    return [(from_stamp(msg.header.stamp), model)]


@dataclass(frozen=True)
class InputTopic:
    """Where one field of ControlInputs comes from."""

    message: type
    topic: Callable[[str], str]  # axis -> topic name
    read: Callable[[Any, str], Samples | Rejected]  # (message, axis) -> its samples
    owner: str  # the parameter naming the node that must send it
    hint: str = ''  # what to run when a law needs this input and none has arrived
    decode: Callable[[bytes], Any] = decode_joint_state  # its CDR bytes -> its fields


# Field of ControlInputs -> its topic. The state paces the node (CLOCK_INPUT); the reference
# is taken at the state's stamp from the points the trajectory sent ahead (ReferenceBuffer).
INPUTS: dict[str, InputTopic] = {
    'position': InputTopic(JointState, topics.state, _position, 'plant_node'),
    'estimate': InputTopic(JointState, topics.estimate, _estimate, 'observer_node'),
    'reference': InputTopic(
        JointTrajectory,
        lambda _axis: topics.REFERENCE,
        _reference,
        'trajectory_node',
        decode=decode_joint_trajectory,
    ),
    'model': InputTopic(
        JointState, topics.observer_state, _model, 'observer_node', 'run the rls observer'
    ),
}
CLOCK_INPUT = 'position'
REFERENCE_INPUT = 'reference'


def owners(values: dict[str, Any]) -> dict[str, str]:
    """The node that must send each input (the observer's default: <axis>_observer)."""
    out = {slot: values[source.owner] for slot, source in INPUTS.items()}
    for slot in ('estimate', 'model'):
        out[slot] = out[slot] or f'{values["axis"]}_observer'
    return out
