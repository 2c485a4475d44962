"""A URDF of the three-axis machine, made from its own declarations. ROS-free.

The machine is a chain of three prismatic joints named after the axes, `x`, `y` and `z`
(the names of `mill/<axis>/state` and of `joint_states`), from `BASE_LINK` through one
carriage per axis to `TOOL_LINK`: the tool's point in `BASE_LINK` is (x, y, z), the frame in
which mill/planned_path and mill/tool_trace are drawn. Each joint's limits are the
machine's: lower/upper from the trajectory's `travel.min`/`travel.max` [m], velocity from
the drive's `speed_limit` [m/s] and effort from the drive's `max_torque` (the drive's input
limit, in the axis model's input unit; a URDF cannot say .inf, so no limit is written as the
largest double). Nothing is copied by hand: `machine_urdf` is called with the values the
nodes are given (mill_bringup.machine_view, the launch plan), so the model follows them.
On the one global /tf the frames of a machine in a namespace carry it (`frame`:
`machine_a/mill_base`), as robot_state_publisher's `frame_prefix` puts it.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from xml.etree import ElementTree

from mill_common.signals import AXES
from mill_common.topics import namespace

BASE_LINK = 'mill_base'
TOOL_LINK = 'tool'
# The direction each axis moves its carriage in BASE_LINK.
AXIS_DIRECTIONS = {'x': '1 0 0', 'y': '0 1 0', 'z': '0 0 1'}
# What a viewer draws of each moving link [m]: a slab per carriage, a cutter at the tool
# (shapes to see the axes move by, not the machine's).
SHAPES = {
    'x_carriage': ('box', {'size': '0.06 0.02 0.005'}),
    'y_carriage': ('box', {'size': '0.02 0.06 0.005'}),
    TOOL_LINK: ('cylinder', {'radius': '0.003', 'length': '0.03'}),
}


@dataclass(frozen=True)
class JointLimits:
    """One prismatic joint's limits as a URDF writes them."""

    lower: float  # [m]
    upper: float  # [m]
    velocity: float  # [m/s]
    effort: float


def frame_prefix(ns: str) -> str:
    """What the frames of the machine in namespace `ns` start with on the one global /tf
    (robot_state_publisher's `frame_prefix`): '' at the root, 'machine_a/' in /machine_a."""
    prefix = namespace(ns).strip('/')
    return f'{prefix}/' if prefix else ''


def frame(link: str, ns: str) -> str:
    """The TF frame of one of the machine's links in namespace `ns` (`machine_a/mill_base`)."""
    return frame_prefix(ns) + link


def _finite(value: float) -> float:
    return float(value) if math.isfinite(value) else sys.float_info.max


def joint_limits(
    travel_min: Sequence[float],
    travel_max: Sequence[float],
    speed_limit: float,
    max_torque: Sequence[float],
) -> dict[str, JointLimits]:
    """Per axis name: its limits from the travel, the drive's speed limit and input limit;
    ValueError (one line) for lists that are not one value per axis or a travel whose min
    exceeds its max."""
    lists = {'travel.min': travel_min, 'travel.max': travel_max, 'max_torque': max_torque}
    for name, values in lists.items():
        if len(values) != len(AXES):
            raise ValueError(f'{name} must have {len(AXES)} values, got {len(values)}')
    out = {}
    for i, axis in enumerate(AXES):
        lo, hi = float(travel_min[i]), float(travel_max[i])
        if not lo <= hi:
            raise ValueError(f'travel of axis {axis}: min {lo} exceeds max {hi}')
        out[axis] = JointLimits(lo, hi, _finite(speed_limit), _finite(max_torque[i]))
    return out


def machine_urdf(limits: dict[str, JointLimits], name: str = 'mill') -> str:
    """The URDF text of the machine with these joints' limits (xml declaration included)."""
    robot = ElementTree.Element('robot', name=name)
    ElementTree.SubElement(robot, 'link', name=BASE_LINK)
    parent = BASE_LINK
    for i, axis in enumerate(AXES):
        child = TOOL_LINK if i == len(AXES) - 1 else f'{axis}_carriage'
        link = ElementTree.SubElement(robot, 'link', name=child)
        shape, size = SHAPES[child]
        visual = ElementTree.SubElement(link, 'visual')
        # the cutter's point at the link's origin, its shank above it
        above = float(size.get('length', '0')) / 2
        ElementTree.SubElement(visual, 'origin', xyz=f'0 0 {above!r}', rpy='0 0 0')
        ElementTree.SubElement(ElementTree.SubElement(visual, 'geometry'), shape, size)
        joint = ElementTree.SubElement(robot, 'joint', name=axis, type='prismatic')
        ElementTree.SubElement(joint, 'parent', link=parent)
        ElementTree.SubElement(joint, 'child', link=child)
        ElementTree.SubElement(joint, 'origin', xyz='0 0 0', rpy='0 0 0')
        ElementTree.SubElement(joint, 'axis', xyz=AXIS_DIRECTIONS[axis])
        lim = limits[axis]
        ElementTree.SubElement(
            joint,
            'limit',
            lower=repr(lim.lower),
            upper=repr(lim.upper),
            velocity=repr(lim.velocity),
            effort=repr(lim.effort),
        )
        parent = child
    ElementTree.indent(robot)
    return ElementTree.tostring(robot, encoding='unicode', xml_declaration=True) + '\n'
