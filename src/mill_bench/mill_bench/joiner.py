"""A client that joins the ROS domain again and again: a participant with a reader of the
reference, kept for PERIOD seconds, then gone; until it is terminated.

    python -m mill_bench.joiner 0.5

What an operator's tool (`ros2 topic echo`, a parameter panel, a test's client) does to a
running graph when it comes and goes. mill_bench.repeat_runs --join-every starts it beside
each run, in the run's domain, and counts the lockstep steps that waited.
"""

from __future__ import annotations

import argparse
import signal
import sys
import time
from collections.abc import Sequence


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog='python -m mill_bench.joiner', description=__doc__)
    parser.add_argument('period', type=float, help='seconds each participant lives (> 0)')
    args = parser.parse_args(argv)
    if not args.period > 0:
        parser.error('period: must be > 0')
    import rclpy
    from mill_common.ros import DATA_QOS
    from rclpy.node import Node
    from trajectory_msgs.msg import JointTrajectory

    from mill_common import topics

    stop = {'now': False}
    signal.signal(signal.SIGTERM, lambda *_: stop.update(now=True))
    joins = 0
    try:
        while not stop['now']:
            context = rclpy.Context()
            rclpy.init(args=[], context=context)
            node = Node(f'joiner_{joins}', context=context)
            node.create_subscription(JointTrajectory, topics.REFERENCE, lambda m: None, DATA_QOS)
            end = time.monotonic() + args.period
            while time.monotonic() < end and not stop['now']:
                time.sleep(0.02)
            node.destroy_node()
            rclpy.shutdown(context=context)
            joins += 1
    except KeyboardInterrupt:
        pass
    print(f'joiner: {joins} participants joined and left', file=sys.stderr)
    return 0


if __name__ == '__main__':
    sys.exit(main())
