"""Per-message cost of identifying the sender by its publisher GID (mill_common.graph_owner).

    python -m mill_bench.owner_cost [N]

Times, in this process, on N messages already waiting in the reader's queue: rclpy's own
raw take (`take_message`, no GID) against the GID take (rcl's through ctypes), and the
graph verdict of a known GID (a dict look-up). Prints µs per message. (What a whole
lockstep job pays: docs/hardware-driver.md, "Who sent it".)
"""

from __future__ import annotations

import os
import sys
import time


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
        got = gid.take_data()
    t2 = time.perf_counter()
    assert got is not None
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
    gid.destroy()
    reader.destroy_subscription(plain)
    writer.destroy_node()
    reader.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
