"""CPU per message of a take: a plain raw subscription against the GID take of an owned input.

    python -m mill_bench.take_cost            # 5000 messages each way, JSON
    python -m mill_bench.take_cost 20000

One process, one node: a publisher sends N serialized JointStates (a state's size), they
queue in a subscription's history, then the node's executor (mill_common.node_main's,
MILL_EXECUTOR) takes them all; the CPU time of that, per message. `plain` is rclpy's raw
subscription (the C++ EventsExecutor calls its callback from C++); `gid` is
mill_common.graph_owner.GidSubscription, as the nodes and the runner take an owned input
(a Waitable: rclpy's executor makes a Task of each message). The messages wait in the
history first, so this is the take alone, with warm caches; in a running graph, where each
message wakes its process, the difference is larger (mill_bench.floor with
MILL_FLOOR_TAKE=gid).
"""

from __future__ import annotations

import json
import sys
import time
from typing import Any

TOPIC = '/mill_take_cost'


def measure(kind: str, count: int) -> float:
    """µs of CPU per message taken by a subscription of `kind` ('plain' or 'gid')."""
    import rclpy
    from mill_common.codec import encode_joint_state
    from mill_common.graph_owner import GidSubscription
    from mill_common.node_main import make_executor
    from rclpy.node import Node
    from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState

    rclpy.init()
    try:
        node = Node(f'mill_take_cost_{kind}')
        qos = QoSProfile(
            reliability=ReliabilityPolicy.RELIABLE,
            history=HistoryPolicy.KEEP_LAST,
            depth=count + 10,
        )
        pub = node.create_publisher(JointState, TOPIC, qos)
        taken = [0]

        def on_message(*_: Any) -> None:
            taken[0] += 1

        if kind == 'gid':
            GidSubscription(node, JointState, TOPIC, on_message, qos)
        else:
            node.create_subscription(JointState, TOPIC, on_message, qos, raw=True)
        executor = make_executor()
        executor.add_node(node)
        for _ in range(10):  # matched, and the executor has the subscription
            executor.spin_once(timeout_sec=0.02)
        data = encode_joint_state(0, 'plant', ('x',), (0.0,))
        for _ in range(count):
            pub.publish(data)
        time.sleep(0.2)
        cpu, deadline = time.process_time(), time.monotonic() + 60.0
        while taken[0] < count and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.1)
        used = time.process_time() - cpu
        if taken[0] < count:
            raise RuntimeError(f'{kind}: {taken[0]} of {count} messages taken')
        return 1e6 * used / count
    finally:
        rclpy.try_shutdown()


def main(argv: list[str] | None = None) -> int:
    from mill_common.env import apply_to_current_process

    args = list(sys.argv[1:] if argv is None else argv)
    if args[:1] in (['-h'], ['--help']) or len(args) > 1 or (args and not args[0].isdigit()):
        print(__doc__)
        return 0 if args[:1] in (['-h'], ['--help']) else 2
    count = int(args[0]) if args else 5000
    apply_to_current_process()
    result = {f'{kind}_us_per_message': measure(kind, count) for kind in ('plain', 'gid')}
    print(json.dumps({'messages': count, **result}))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
