"""What a drive's configure decides before it makes anything, ROS-free: whether its timing,
its backend and the ros2_control topic pair go together, and who commands each axis
(mill_plant.drive_node makes the topics, the intake and the ownership from that).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from mill_plant.topic_pair import Ros2ControlParams

MACHINE_AXES = ('x', 'y', 'z')  # the axes of `command_owners`, in its order


def configure_refusal(grid: bool, simulated: bool, pair: Ros2ControlParams) -> str | None:
    """Why a drive cannot be configured so (one line), or None. grid: its timing steps on
    the sample grid (lockstep); simulated: its backend is a simulation."""
    if grid and not simulated:
        return 'a real machine cannot run in lockstep: use timing realtime'
    if pair.commands_topic and grid:
        return (
            'ros2_control.commands_topic needs timing realtime: the controller manager runs '
            'its own loop on the wall clock and never answers a lockstep step'
        )
    return None


@dataclass(frozen=True)
class CommandOwners:
    """Who may command the drive's axes, by the graph's name of the node."""

    axis_topics: dict[str, str]  # the owner of each axis's mill/<axis>/joint_command
    axes: dict[str, str]  # who commands each axis: its controller, or the pair's owner
    pair_topics: dict[str, str] | None  # the pair's two topics and their owners; None: no pair


def command_owners(
    axes: Sequence[str], configured: Sequence[str], pair: Ros2ControlParams, drive: str
) -> CommandOwners:
    """The owners of the axes a backend has, from `command_owners` (one per MACHINE_AXES);
    with the topic pair its owner commands every axis, and the drive owns its states."""
    owners = dict(zip(MACHINE_AXES, configured, strict=True))
    axis_topics = {a: owners[a] for a in axes}
    if not pair.commands_topic:
        return CommandOwners(axis_topics, axis_topics, None)
    pair_topics = {pair.commands_topic: pair.owner, pair.states_topic: drive}
    return CommandOwners(axis_topics, dict.fromkeys(axes, pair.owner), pair_topics)
