"""Monitor: listens to a run's topics and rebuilds its RunRecord.

Subscriptions take the serialized bytes (no Python message per sample while
the run goes on); messages are decoded once at the end.
"""

from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticArray
from mill_common.ros import DATA_QOS, from_duration, from_stamp
from mill_common.signals import AXES
from rclpy.node import Node
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from mill_bringup.metrics import RunRecord
from mill_common import topics


class Monitor(Node):
    def __init__(self, axes: list[str], name: str = 'mill_monitor') -> None:
        super().__init__(name)
        self.axes = axes
        self.raw: dict[str, list[bytes]] = {}
        self.last_stamp_ns = -1
        self.diagnostics: list[DiagnosticArray] = []
        self._types = {}
        # What the summary needs; commands and forces are for the recorder.
        for axis in axes:
            self._listen(topics.state(axis), JointState, track=(axis == axes[0]))
            self._listen(topics.estimate(axis), JointState)
        self._listen(topics.REFERENCE, JointTrajectory)
        self._listen(topics.GROUND_TRUTH, JointState)
        self.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, self.diagnostics.append, 100)

    def _listen(self, topic: str, msg_type: type, track: bool = False) -> None:
        store = self.raw.setdefault(topic, [])
        self._types[topic] = msg_type
        if track:
            # Progress: decode only the stamp of one topic.
            def on_msg(data: bytes) -> None:
                store.append(data)
                self.last_stamp_ns = from_stamp(deserialize_message(data, msg_type).header.stamp)
        else:
            on_msg = store.append
        self.create_subscription(msg_type, topic, on_msg, DATA_QOS, raw=True)

    def count(self, topic: str) -> int:
        return len(self.raw.get(topic, ()))

    def record(self, n: int, dt_ns: int) -> tuple[RunRecord, dict[str, int]]:
        """Decode into a RunRecord of n samples; also return samples missing per topic."""
        rec = RunRecord.empty(n, dt_ns / 1e9)
        s = rec.signals
        missing: dict[str, int] = {}

        def rows(topic: str, chunks: bool = False):
            msg_type = self._types.get(topic)
            if msg_type is None:
                return  # not listened to
            seen = set()
            for data in self.raw.get(topic, ()):
                msg = deserialize_message(data, msg_type)
                k, rem = divmod(from_stamp(msg.header.stamp), dt_ns)
                if rem == 0 and 0 <= k < n:
                    seen.add(k)
                    yield k, msg
            if not chunks:
                missing[topic] = n - len(seen)

        for axis in self.axes:
            i = AXES.index(axis)
            for k, msg in rows(topics.state(axis)):
                s['position'][k, i] = msg.position[0]
            for k, msg in rows(topics.estimate(axis)):
                s['estimate_velocity'][k, i] = msg.velocity[0]
                s['estimate_disturbance'][k, i] = msg.effort[0]
            for k, msg in rows(topics.joint_command(axis)):
                s['torque'][k, i] = msg.effort[0]
        for k0, msg in rows(topics.REFERENCE, chunks=True):
            for point in msg.points:
                k = k0 + from_duration(point.time_from_start) // dt_ns
                if k >= n:
                    break
                for j, name in enumerate(msg.joint_names):
                    if name in self.axes:
                        i = AXES.index(name)
                        s['reference'][k, i] = point.positions[j]
                        s['reference_velocity'][k, i] = point.velocities[j]
        for k, msg in rows(topics.GROUND_TRUTH):
            for j, name in enumerate(msg.name):
                i = AXES.index(name)
                s['true_velocity'][k, i] = msg.velocity[j]
                s['true_disturbance'][k, i] = msg.effort[j]
        for k, msg in rows(topics.CUTTING_FORCE):
            f = msg.wrench.force
            s['force'][k] = (f.x, f.y, f.z)
        return rec, missing


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
