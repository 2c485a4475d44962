"""Machine view node: what RViz and Foxglove need to draw the machine and the tool's trace.

    ros2 run mill_bringup machine_view --ros-args -r __ns:=/machine2

Publishes, under its namespace:

- `robot_description` (std_msgs/String, transient local): the machine's URDF (parameter
  `robot_description`; the launch gives the job's, mill_bringup.machine_model; empty: the
  machine of the declared defaults), for robot_state_publisher and the viewers;
- `mill/tool_trace` (nav_msgs/Path): the measured x, y, z of the tool from `mill/<axis>/state`,
  at most `trace_rate` points per second of the states' stamps, the newest `trace_length`
  (mill_common.tool_path.TraceDecimator), published each time a point is added.

A thin adapter: which points the trace keeps is decided ROS-free. A malformed state is
dropped with one line (throttled) and the node keeps running.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any, ClassVar

from mill_common.codec import decode_joint_state
from mill_common.declared import ParamSet, param
from mill_common.node_main import run_node
from mill_common.parameters import ParamSpec, in_range, positive_int, text
from mill_common.path_msgs import path_message
from mill_common.ros import DATA_QOS, LATCHED_QOS, from_stamp, take_serialized
from mill_common.ros_params import NodeParameters
from mill_common.signals import AXES
from mill_common.tool_path import TRACE_LENGTH, TRACE_RATE, TraceDecimator
from nav_msgs.msg import Path
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_msgs.msg import String

from mill_common import topics


@dataclass(frozen=True)
class MachineViewParams(ParamSet):
    PREFIX: ClassVar[str] = ''
    robot_description: str = param(
        '',
        "the machine's URDF, published on robot_description; empty: the machine of the "
        'declared defaults (the launch gives the one of the job: its travel, speed limit '
        'and drive input limit)',
        text,
        read_only=True,
    )
    trace_rate: float = param(
        TRACE_RATE,
        "points of mill/tool_trace per second of the states' stamps, at most",
        in_range(0.01, 1000.0),
        unit='Hz',
        read_only=True,
    )
    trace_length: int = param(
        TRACE_LENGTH,
        'points mill/tool_trace keeps (the newest)',
        positive_int,
        read_only=True,
    )


def parameter_specs() -> list[tuple[str, ParamSpec]]:
    return MachineViewParams.named_specs()


class MachineView(Node):
    def __init__(self, **options: Any) -> None:
        super().__init__('machine_view', **options)
        self.trace: TraceDecimator  # made by _configure
        self.params = NodeParameters(self, parameter_specs(), self._configure)
        v = self.params.values
        self._description = self.create_publisher(String, topics.ROBOT_DESCRIPTION, LATCHED_QOS)
        self._description.publish(String(data=v['robot_description'] or _default_urdf()))
        self._trace = self.create_publisher(Path, topics.TOOL_TRACE, 10)
        for axis in AXES:
            on_state: Callable[[Any], None] = partial(self._on_state, axis)
            on_bad: Callable[[Any], None] = partial(self._bad, axis)
            topic = topics.state(axis)
            take_serialized(self, JointState, topic, decode_joint_state, on_state, DATA_QOS, on_bad)
        self.get_logger().info(
            f'URDF on {self.resolve_topic_name(topics.ROBOT_DESCRIPTION)}, tool trace on '
            f'{self.resolve_topic_name(topics.TOOL_TRACE)} at {v["trace_rate"]:g} Hz'
        )

    def _configure(self, values: dict[str, Any]) -> None:
        period_ns = max(1, round(1e9 / values['trace_rate']))
        self.trace = TraceDecimator(AXES, period_ns, values['trace_length'])

    def _on_state(self, axis: str, msg: Any) -> None:
        if not len(msg.position):
            self._bad(axis, 'a state without a position')
            return
        if self.trace.take(axis, from_stamp(msg.header.stamp), float(msg.position[0])):
            stamps, points = zip(*self.trace.points, strict=True)
            self._trace.publish(path_message(stamps[-1], points, stamps, self.get_namespace()))

    def _bad(self, axis: str, problem: object) -> None:
        self.get_logger().warning(
            f'dropped a message on {topics.state(axis)}: {problem}', throttle_duration_sec=5.0
        )


def _default_urdf() -> str:
    from mill_bringup.machine_model import robot_description

    return robot_description()


def main(argv: list[str] | None = None) -> int:
    return run_node(
        MachineView,
        'machine_view',
        "Publishes the machine's URDF on robot_description and the measured tool trace on "
        'mill/tool_trace (nav_msgs/Path) for RViz and Foxglove.',
        parameter_specs(),
        argv,
    )


if __name__ == '__main__':
    raise SystemExit(main())
