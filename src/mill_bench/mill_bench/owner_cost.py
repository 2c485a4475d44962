"""Per-message cost of identifying the sender by its publisher GID (mill_common.graph_owner).

    python -m mill_bench.owner_cost [N]

Times, in this process, on N messages already waiting in the reader's queue: rclpy's own
raw take (`take_message`, no GID) against the GID take (rcl's through ctypes), and the
graph verdict of a known GID (a dict look-up); then the whole way through the executor the
nodes run (mill_common.node_main.make_executor: the C++ EventsExecutor) from the queue to
the callback, a raw subscription against a GidSubscription. Prints µs per
message.
"""

from __future__ import annotations

import os
import sys
import time
from typing import Any


def main(argv: list[str] | None = None) -> int:
    import rclpy
    from mill_common.graph_owner import GidSubscription, GraphOwners
    from mill_common.ros import joint_state_bytes
    from rclpy.node import Node
    from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState

    n = int((argv or sys.argv[1:] or ['2000'])[0])
    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    os.environ.setdefault('ROS_DOMAIN_ID', str(150 + os.getpid() % 70))
    rclpy.init(args=[])
    qos = QoSProfile(reliability=ReliabilityPolicy.RELIABLE, history=HistoryPolicy.KEEP_ALL)
    writer, reader = Node('x_controller'), Node('plant')
    pub = writer.create_publisher(JointState, 'cmd', qos)
    plain = reader.create_subscription(JointState, 'cmd', lambda m: None, qos, raw=True)
    gid = GidSubscription(reader, JointState, 'cmd', lambda d, g: None, qos)
    time.sleep(1.0)  # discovery
    msg = joint_state_bytes(0, ('x',), effort=(0.5,), sender='x_controller')
    for _ in range(n):
        pub.publish(msg)
    time.sleep(1.0)  # all delivered to both readers
    t0 = time.perf_counter()
    for _ in range(n):
        with plain.handle:
            plain.handle.take_message(JointState, True)
    t1 = time.perf_counter()
    got = None
    for _ in range(n):
        with gid.handle:
            got = gid.handle.take_message(JointState, True)
    t2 = time.perf_counter()
    assert got is not None
    got = got[0]
    graph = GraphOwners(reader)
    topic = graph.watch('cmd', 'x_controller')
    assert graph.verdict(topic, got[1]).verdict == 'owner'
    t3 = time.perf_counter()
    for _ in range(n):
        graph.verdict(topic, got[1])
    t4 = time.perf_counter()
    us = 1e6 / n
    print(f'rclpy raw take (no GID): {(t1 - t0) * us:.2f} µs/message')
    print(f'GID take (rcl via ctypes): {(t2 - t1) * us:.2f} µs/message')
    print(f'graph verdict of a known GID: {(t4 - t3) * us:.3f} µs/message')
    reader.destroy_subscription(gid)
    reader.destroy_subscription(plain)
    for label, make in (
        (
            'raw subscription',
            lambda cb: reader.create_subscription(JointState, 'e', cb, qos, raw=True),
        ),
        ('GidSubscription', lambda cb: GidSubscription(reader, JointState, 'e', cb, qos)),
    ):
        took = _through_executor(writer, reader, make, n)
        print(f'{label} through the executor: {took:.2f} µs/message')
    writer.destroy_node()
    reader.destroy_node()
    rclpy.try_shutdown()
    return 0


def _through_executor(writer: Any, reader: Any, make: Any, n: int) -> float:
    """µs per message from the reader's queue to its callback, through make_executor()."""
    from mill_common.node_main import make_executor
    from mill_common.ros import joint_state_bytes
    from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState

    qos = QoSProfile(reliability=ReliabilityPolicy.RELIABLE, history=HistoryPolicy.KEEP_ALL)
    got = [0]

    def count(*_: Any) -> None:
        got[0] += 1

    sub = make(count)
    pub = writer.create_publisher(JointState, 'e', qos)
    time.sleep(1.0)
    msg = joint_state_bytes(0, ('x',), effort=(0.5,), sender='x_controller')
    for _ in range(n):
        pub.publish(msg)
    time.sleep(1.0)
    executor = make_executor()
    executor.add_node(reader)
    t0 = time.perf_counter()
    end = t0 + 30.0
    while got[0] < n and time.perf_counter() < end:
        executor.spin_once(timeout_sec=0.1)
    took = time.perf_counter() - t0
    executor.remove_node(reader)
    executor.shutdown()
    writer.destroy_publisher(pub)
    reader.destroy_subscription(sub)
    assert got[0] == n, f'{got[0]} of {n} messages'
    return took * 1e6 / n


if __name__ == '__main__':
    raise SystemExit(main())
