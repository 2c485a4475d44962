"""The floor of the realtime loop: one process that answers every state at once.

    python -m mill_bench.echo x y z [--limit SECONDS]

A node `mill_echo` subscribes to mill/<axis>/state of every axis given and answers each
state with a command on mill/<axis>/joint_command: stamped like the state, name [axis],
effort [0.0], header.frame_id its own name. The drive takes it as it takes a controller's
once it is told that this node owns the axes (`command_owners`). Serialized take and
publish, as the nodes do (mill_common.ros): what the drive measures against this node is
what transport and executor allow, with no observer, no controller and no work of ours
between state and command. It takes the states as the realtime nodes take their inputs
(mill_common.timing.Realtime): only the newest queues, so that states that discovery held
back and delivered at once are not answered one by one, late. Ends on SIGINT or after
--limit s (default 600).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence
from typing import Any

from mill_common.codec import JointStateData, decode_joint_state
from mill_common.env import apply_to_current_process
from mill_common.ros import (
    DATA_QOS,
    data_publisher,
    from_stamp,
    joint_state_bytes,
    take_serialized,
)
from mill_common.timing import Realtime

from mill_bench.pingpong import serve
from mill_common import topics

NAME = 'mill_echo'  # the node, and the sender of its commands


def build(axes: Sequence[str]) -> Callable[[Any, list[Any]], None]:
    """The echo's endpoints: per axis, a command answering each state."""
    depth = Realtime(0).depth()
    qos = DATA_QOS if depth is None else depth

    def make(node: Any, done: list[Any]) -> None:
        from sensor_msgs.msg import JointState

        for axis in axes:
            pub = data_publisher(node, JointState, topics.joint_command(axis), DATA_QOS)

            def answer(msg: JointStateData, axis: str = axis, pub: Any = pub) -> None:
                ns = from_stamp(msg.header.stamp)
                pub.publish(joint_state_bytes(ns, (axis,), effort=(0.0,), sender=NAME))

            take_serialized(
                node,
                JointState,
                topics.state(axis),
                decode_joint_state,
                answer,
                qos,
                lambda problem: None,  # the drive's states only: nothing else comes
            )

    return make


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog='python -m mill_bench.echo', description=__doc__)
    parser.add_argument('axes', nargs='+', help='the axes to answer, e.g. x y z')
    parser.add_argument('--limit', type=float, default=600.0, help='end after this long [s]')
    args = parser.parse_args(argv)
    apply_to_current_process()
    serve(NAME, build(args.axes), args.limit)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
