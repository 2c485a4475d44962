"""A node's statuses on /diagnostics: one publisher per node, names `[<ns>/]<node>: <part>`.

Every node reports through one `Diagnostics`: its statuses are named after the node and
the topic or part they are about (`x_controller: inputs`, `plant: x axis`,
`trajectory: job`; in a namespace, `machine_a/x_controller: inputs`: topics.status_name),
their hardware_id is the machine's namespace, and `report` also puts
the message in the node's log at the matching severity. A reader finds a status by its
part whatever the node is called (mill_common.topics.part_of).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rclpy.node import Node

from mill_common import topics
from mill_common.ros import diagnostic_status, diagnostics_of


class Diagnostics:
    def __init__(self, node: Node) -> None:
        self.node = node
        self.publisher = node.create_publisher(DiagnosticArray, topics.DIAGNOSTICS, 10)

    @property
    def machine(self) -> str:
        """hardware_id of the node's statuses: the machine's namespace."""
        return topics.machine_id(self.node.get_namespace())

    def status(
        self, level: bytes, part: str, message: str, values: Mapping[str, object] | None = None
    ) -> DiagnosticStatus:
        name = topics.status_name(self.node.get_name(), part, self.node.get_namespace())
        return diagnostic_status(level, name, message, self.machine, values)

    def publish(self, stamp_ns: int, statuses: Sequence[DiagnosticStatus]) -> None:
        self.publisher.publish(diagnostics_of(stamp_ns, statuses))

    def report(
        self,
        stamp_ns: int,
        level: bytes,
        part: str,
        message: str,
        values: Mapping[str, object] | None = None,
        log: bool = True,
    ) -> None:
        """Publish one status now, and log its message at its level."""
        if log:
            logger = self.node.get_logger()
            # rclpy wants one severity per call site: one call each.
            if level == DiagnosticStatus.OK:
                logger.info(message)
            elif level == DiagnosticStatus.WARN:
                logger.warning(message)
            else:
                logger.error(message)
        self.publish(stamp_ns, [self.status(level, part, message, values)])
