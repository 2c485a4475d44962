"""Monitor: listens to a run's topics, rebuilds its RunRecord and, if asked, records the run.

Subscriptions take the serialized bytes (no Python message per sample while
the run goes on); messages are decoded once at the end by the same function
that reads bags (`mill_bringup.run_record.record_from_raw`), so the runner's summary and
the report of the run's bag are computed by the same code.

With `record=RecordOptions(...)` a TopicRecorder writes every topic of the
graph to a rosbag2 bag: the monitor's own subscriptions feed it too, and it
subscribes only to the topics the summary does not need (commands, cutting
force, /clock, /diagnostics, and whatever else discovery finds).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import WrenchStamped
from mill_bag.cdr import cdr_stamp_ns
from mill_bag.recorder import TopicRecorder
from mill_bag.types import CLOCK, DIAGNOSTIC_ARRAY, JOINT_STATE, JOINT_TRAJECTORY, WRENCH_STAMPED
from mill_common.ros import DATA_QOS
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from mill_bringup.metrics import RunRecord
from mill_bringup.run_record import record_from_raw
from mill_common import topics

TYPE_NAMES = {
    JointState: JOINT_STATE,
    JointTrajectory: JOINT_TRAJECTORY,
    WrenchStamped: WRENCH_STAMPED,
    Clock: CLOCK,
    DiagnosticArray: DIAGNOSTIC_ARRAY,
}


@dataclass(frozen=True)
class RecordOptions:
    path: Path
    sim_time: bool = True
    compression: str = 'zstd'


class Monitor(Node):
    def __init__(
        self, axes: list[str], name: str = 'mill_monitor', record: RecordOptions | None = None
    ) -> None:
        super().__init__(name)
        self.axes = axes
        self.raw: dict[str, list[bytes]] = {}
        self.last_stamp_ns = -1
        self.diagnostics: list[DiagnosticArray] = []
        self._types: dict[str, str] = {}
        self.recorder = None
        if record is not None:
            self.recorder = TopicRecorder(
                self, record.path, sim_time=record.sim_time, compression=record.compression
            )
        # What the summary needs.
        for axis in axes:
            self._listen(topics.state(axis), JointState, track=(axis == axes[0]))
            self._listen(topics.estimate(axis), JointState)
        self._listen(topics.REFERENCE, JointTrajectory)
        self._listen(topics.GROUND_TRUTH, JointState)
        self.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, self.diagnostics.append, 100)
        if self.recorder is not None:
            # The rest of the contract, subscribed before the graph starts so that the
            # first step is recorded; discovery adds any other topic.
            for axis in axes:
                self.recorder.subscribe(topics.joint_command(axis), JOINT_STATE, DATA_QOS)
            self.recorder.subscribe(topics.CUTTING_FORCE, WRENCH_STAMPED, DATA_QOS)
            self.recorder.subscribe(topics.CLOCK, CLOCK, DATA_QOS)
            diag_qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
            self.recorder.subscribe(topics.DIAGNOSTICS, DIAGNOSTIC_ARRAY, diag_qos)

    def _listen(self, topic: str, msg_type: type, track: bool = False) -> None:
        store = self.raw.setdefault(topic, [])
        type_name = TYPE_NAMES[msg_type]
        self._types[topic] = type_name
        keep = store.append
        tap = self.recorder.tap(topic, type_name) if self.recorder is not None else None
        if track:
            # Progress: the stamp of one topic, read from the serialized header.
            def on_msg(data: bytes) -> None:
                keep(data)
                self.last_stamp_ns = cdr_stamp_ns(data)
                if tap is not None:
                    tap(data)
        elif tap is not None:

            def on_msg(data: bytes) -> None:
                keep(data)
                tap(data)
        else:
            on_msg = keep
        self.create_subscription(msg_type, topic, on_msg, DATA_QOS, raw=True)

    def count(self, topic: str) -> int:
        return len(self.raw.get(topic, ()))

    def latest_stamp_ns(self, topic: str) -> int:
        """Stamp of the newest message of a topic (one writer delivers in order), -1 if none.

        Counting messages is not enough to know a topic is complete: a step
        offered twice at the start is answered twice.
        """
        store = self.raw.get(topic)
        stamp = cdr_stamp_ns(store[-1]) if store else None
        return -1 if stamp is None else stamp

    def record(self, n: int, dt_ns: int) -> tuple[RunRecord, dict[str, int]]:
        """Decode into a RunRecord of n samples; also return samples missing per topic."""
        return record_from_raw(self.raw, self._types, self.axes, n, dt_ns)

    def close_recording(self) -> None:
        """Write what is buffered and close the bag (idempotent)."""
        if self.recorder is None:
            return
        try:
            self.recorder.close()
        except ValueError:
            if self.recorder.error is None:
                raise  # a new failure; an earlier one has been reported already


def job_done_time(diagnostics: list[DiagnosticArray], status_name: str) -> float | None:
    """The time at which the trajectory reported the job done, if it has."""
    for array in diagnostics:
        for status in array.status:
            if status.name != status_name:
                continue
            values = {kv.key: kv.value for kv in status.values}
            if values.get('state') == 'done':
                return float(values.get('time', 'nan'))
    return None


def plant_status(diagnostics: list[DiagnosticArray], status_name: str) -> dict[str, str]:
    """The plant's last lockstep status values."""
    for array in reversed(diagnostics):
        for status in array.status:
            if status.name == status_name:
                return {kv.key: kv.value for kv in status.values} | {'message': status.message}
    return {}
