"""Job watch node: ends when the trajectory of its machine reports the job done.

    ros2 run mill_bringup job_watch --ros-args -r __ns:=/machine2

The launch file starts it beside a scenario's nodes and ends the launch when it exits, so
that `ros2 launch` ends by itself with the job (run_scenario follows the job itself). It
listens to /diagnostics for the status `<trajectory>: job` whose hardware_id is its own
namespace (mill_common.topics.from_machine) and exits with code 0 once that status says
`done`.
"""

from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticArray
from mill_common.node_main import request_exit, run_node
from mill_common.parameters import ParamSpec
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy

from mill_common import topics


def parameter_specs() -> list[tuple[str, ParamSpec]]:
    return []


class JobWatch(Node):
    def __init__(self) -> None:
        super().__init__('job_watch')
        qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
        self.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, self._on_status, qos)
        self.get_logger().info(
            f'waiting for the job of machine {topics.machine_id(self.get_namespace())} to end'
        )

    def _on_status(self, msg: DiagnosticArray) -> None:
        for status in msg.status:
            if topics.part_of(status.name) != topics.JOB_STATUS:
                continue
            if not topics.from_machine(status.hardware_id, self.get_namespace()):
                continue
            values = {kv.key: kv.value for kv in status.values}
            if values.get('state') == 'done':
                end = values.get('end_time', values.get('time', '?'))
                request_exit(self, 0, f'job done at t = {end} s')


def main(argv: list[str] | None = None) -> int:
    return run_node(
        JobWatch,
        'job_watch',
        'Ends when the trajectory of its machine (its namespace) reports the job done on '
        '/diagnostics; the launch file ends the launch with it.',
        parameter_specs(),
        argv,
    )


if __name__ == '__main__':
    raise SystemExit(main())
