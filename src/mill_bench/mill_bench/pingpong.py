"""Plain rclpy ping-pong between two processes: the transport's limit for lockstep.

    python -m mill_bench.pingpong pong &      # echoes /mill_bench/ping to /mill_bench/pong
    python -m mill_bench.pingpong ping 5000   # prints round-trip statistics as JSON

Same message type (JointState), QoS and executor as the lockstep nodes.
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from mill_common.env import apply_to_current_process
from mill_common.node_main import make_executor
from mill_common.ros import DATA_QOS, joint_state

PING, PONG = '/mill_bench/ping', '/mill_bench/pong'


def serve(
    name: str, build: Callable[[Any, list[Any]], None], limit: float, like_nodes: bool = False
) -> list[Any]:
    """One benchmark process: a node `name` whose endpoints `build(node, done)` makes, spun
    until something is put in `done`, SIGINT, or `limit` seconds (never outlive a lost run).
    Returns `done`.

    like_nodes: spun as a node process spins (mill_common.node_main.run_nodes: the executor
    runs callbacks until a future is done, 0.2 s at most between two looks), not one callback
    per spin_once: with the C++ EventsExecutor a Waitable's message (a GID take) is two
    events, its take and its Task, and each spin_once ends after one."""
    import rclpy
    from rclpy.executors import ExternalShutdownException
    from rclpy.node import Node
    from rclpy.task import Future

    rclpy.init()
    ended = Future()
    done: list[Any] = _Done(ended) if like_nodes else []
    try:
        node = Node(name)
        build(node, done)
        executor = make_executor()
        executor.add_node(node)
        deadline = time.monotonic() + limit
        while not done and rclpy.ok() and time.monotonic() < deadline:
            if like_nodes:
                executor.spin_until_future_complete(ended, timeout_sec=0.2)
            else:
                executor.spin_once(timeout_sec=0.2)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass  # SIGINT: in the executor's wait, rclpy's handler shuts the context down
    finally:
        rclpy.try_shutdown()
    return done


class _Done(list[Any]):
    """`done` that also completes a future when something is put in it."""

    def __init__(self, future: Any) -> None:
        super().__init__()
        self._future = future

    def append(self, item: Any) -> None:
        super().append(item)
        if not self._future.done():
            self._future.set_result(True)


def pong() -> int:
    from sensor_msgs.msg import JointState

    def build(node: Any, done: list[Any]) -> None:
        pub = node.create_publisher(JointState, PONG, DATA_QOS)

        def echo(msg: JointState) -> None:
            if msg.name and msg.name[0] == 'stop':
                done.append(True)
            pub.publish(msg)

        node.create_subscription(JointState, PING, echo, DATA_QOS)

    serve('mill_pong', build, 300.0)
    return 0


def ping(count: int, timeout: float = 60.0) -> dict:
    import rclpy
    from rclpy.node import Node
    from sensor_msgs.msg import JointState

    rclpy.init()
    try:
        node = Node('mill_ping')
        pub = node.create_publisher(JointState, PING, DATA_QOS)
        rtts: list[float] = []
        sent = [0.0]

        def on_pong(msg: JointState) -> None:
            rtts.append(time.perf_counter() - sent[0])
            if len(rtts) < count:
                sent[0] = time.perf_counter()
                pub.publish(joint_state(len(rtts), ('x',), position=(0.0,)))

        node.create_subscription(JointState, PONG, on_pong, DATA_QOS)
        executor = make_executor()
        executor.add_node(node)
        deadline = time.monotonic() + timeout
        while pub.get_subscription_count() < 1 or node.count_publishers(PONG) < 1:
            if time.monotonic() > deadline:
                raise TimeoutError('the pong process never appeared')
            executor.spin_once(timeout_sec=0.1)
        settle = time.monotonic() + 1.0  # discovery settles on the other side too
        while time.monotonic() < settle:
            executor.spin_once(timeout_sec=0.05)
        start = time.perf_counter()
        cpu = time.process_time()
        sent[0] = time.perf_counter()
        pub.publish(joint_state(0, ('x',), position=(0.0,)))
        while len(rtts) < count:
            if time.monotonic() > deadline:
                raise TimeoutError(f'only {len(rtts)} of {count} round trips in {timeout:g} s')
            executor.spin_once(timeout_sec=0.5)
        wall = time.perf_counter() - start
        cpu = time.process_time() - cpu
        stop = JointState()
        stop.name = ['stop']
        pub.publish(stop)
        end = time.monotonic() + 0.3
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.05)
    finally:
        rclpy.try_shutdown()
    r = np.array(rtts) * 1e3
    return {
        'round_trips': count,
        'round_trips_per_second': count / wall,
        'median_ms': float(np.median(r)),
        'p99_ms': float(np.percentile(r, 99)),
        'ping_cpu_us_per_round_trip': 1e6 * cpu / count,
    }


def main(argv: list[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    apply_to_current_process()
    if args[:1] == ['pong']:
        return pong()
    if args[:1] == ['ping']:
        count = int(args[1]) if len(args) > 1 else 5000
        print(json.dumps(ping(count)))
        return 0
    print(__doc__)
    return 2


if __name__ == '__main__':
    raise SystemExit(main())
