"""ros2_control's side of the drive: topic_based_ros2_control's topic pair. ROS-free.

topic_based_ros2_control (PickNikRobotics) is a ros2_control hardware interface
(`topic_based_ros2_control/TopicBasedSystem`) that speaks to a robot over two topics: at
each `write()` of the controller manager it publishes the commands of every joint of its
`<ros2_control>` block as one `sensor_msgs/JointState` on `joint_commands_topic`, each command
interface in the field of its name (position, velocity, effort); at each `read()` it takes the
newest `sensor_msgs/JointState` of `joint_states_topic` (position always, velocity and effort
when given). It stamps a command with its own node's clock at the write (not with the state
it answers) and leaves `header.frame_id` empty; its node is named
`topic_based_ros2_control_<name of the ros2_control block>`.

The drive (mill_plant.drive_node, `timing: realtime` only) can take its commands from that
pair instead of its axes' controllers (`ros2_control.commands_topic`), and publishes the
state pair for the hardware interface to read (mill_plant.ros2_control_adapter, the ROS
side). Here is what decides which such commands it takes:

- `command_shape`: a command names joints of the drive only, each once, and carries one
  effort per joint and nothing else. A position or velocity command is refused: the drive
  applies efforts (motor torque, or amplifier voltage), as ros2_control's `effort` command
  interface gives them; it has no position or velocity loop of its own to close, and a
  block with both would send the unclaimed interface's value (0.0) beside the claimed one.
- `sender_clock`: the stamp is the sender's write time on its clock, so it cannot name a
  state the drive published; it must lie between the oldest state the drive still keeps and
  one period past the drive's now (the same system clock on one host, or synchronised).
- per axis, the drive's own intake (mill_plant.command_intake, `frame_id_says=False`):
  only the owner (`ros2_control.owner`, identified by its publisher GID), newest first, NaN
  the owner's brake request.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

from mill_common.checks import Rejected
from mill_common.declared import ParamSet, param
from mill_common.parameters import Constraint

# A topic name as ROS accepts it, relative or absolute ('' is checked apart).
_TOPIC = re.compile(r'^[~/]?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*$')
_NODE = re.compile(r'^[A-Za-z_][A-Za-z0-9_]*$')


class RosName(Constraint):
    """A ROS topic name (relative or absolute; `off`: '' too) or node name (`node`)."""

    def __init__(self, node: bool = False, off: bool = False) -> None:
        self.pattern, what = (_NODE, 'a node name') if node else (_TOPIC, 'a topic name')
        self.off = off
        self.form = 'letters, digits, _' + ('' if node else ', its parts between /')
        self.text = what + (', or "" for off' if off else '')

    def __call__(self, value: Any) -> str | None:
        if not isinstance(value, str):
            return 'must be a string'
        if (value or not self.off) and not self.pattern.match(value):
            return f'must be {self.text} ({self.form})'
        return None


@dataclass(frozen=True)
class Ros2ControlParams(ParamSet):
    """The drive's topic pair for topic_based_ros2_control (docs/hardware-driver.md,
    "ros2_control")."""

    PREFIX: ClassVar[str] = 'ros2_control'
    commands_topic: str = param(
        '',
        "realtime: take every axis's effort from this topic instead of mill/<axis>/joint_command "
        "(topic_based_ros2_control's joint_commands_topic: one sensor_msgs/JointState naming "
        'the joints x, y, z with one effort each; position or velocity commands are refused); '
        '"" = off. Relative names take the node\'s namespace',
        RosName(off=True),
        read_only=True,
    )
    states_topic: str = param(
        'robot_joint_states',
        'with commands_topic: where the drive publishes every sample the measured position, '
        'velocity and applied effort (NaN: braked) of x, y, z in one sensor_msgs/JointState '
        "(topic_based_ros2_control's joint_states_topic)",
        RosName(),
        read_only=True,
    )
    owner: str = param(
        'topic_based_ros2_control_mill',
        'with commands_topic: the node whose commands the drive takes (its publisher GID in the '
        'graph): topic_based_ros2_control names its node topic_based_ros2_control_<the '
        "ros2_control block's name>; commands from any other node are ignored and reported",
        RosName(node=True),
        read_only=True,
    )


REFUSED_FIELDS = (
    'the drive takes efforts only: give the joints one command_interface "effort" '
    "(ros2_control's effort interface), no position or velocity"
)


def command_shape(
    names: Sequence[str],
    position: Sequence[float],
    velocity: Sequence[float],
    effort: Sequence[float],
    axes: Sequence[str],
) -> Rejected | None:
    """Whether a command of the pair has the shape the drive takes (None: it has): joints
    of the drive only, each once, one effort each, no position or velocity."""
    names = list(names)
    if position or velocity:
        given = ' and '.join(f for f, v in (('position', position), ('velocity', velocity)) if v)
        return Rejected(f'{given} commands refused: {REFUSED_FIELDS}')
    if not names:
        return Rejected('names no joint')
    unknown = [n for n in names if n not in axes]
    if unknown:
        return Rejected(f'joints {unknown} are not axes of this drive {list(axes)}')
    if len(set(names)) != len(names):
        return Rejected(f'names a joint twice: {names}')
    if len(effort) != len(names):
        return Rejected(f'effort has {len(effort)} entries for the {len(names)} joints {names}')
    return None


def sender_clock(
    ns: int, oldest_state_ns: int | None, now_ns: int, lead_ns: int
) -> Rejected | None:
    """Whether a command stamped ns on its sender's clock is recent (None: it is): not
    before the oldest state the drive keeps, not later than now + lead_ns."""
    if oldest_state_ns is None:
        return Rejected('no state published yet')
    if ns < oldest_state_ns:
        return Rejected(
            f'stamp {ns / 1e9:.6f} s is older than every state this drive keeps '
            f'(the oldest {oldest_state_ns / 1e9:.6f} s): stale, or not the system clock'
        )
    if ns > now_ns + lead_ns:
        return Rejected(
            f"stamp {ns / 1e9:.6f} s is {(ns - now_ns) / 1e9:.3f} s ahead of the drive's clock"
        )
    return None
