"""The job server takes a goal's machine time from the clock that goal's machine keeps
(issue 34): with `private_clock` in a namespace, NAMESPACE/clock and never the global /clock
(another machine's). Real rclpy nodes in this process, a private domain; the goal is taken
as the action server takes it (its goal callback), without starting the runner."""

from __future__ import annotations

import os
import time
from typing import Any

import pytest


def test_a_private_clock_goal_follows_its_own_clock_and_not_the_global_one(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from mill_bringup.job_server import JobServer
    from mill_common.in_process import node_factory
    from mill_interfaces.action import RunJob
    from rclpy.action import GoalResponse
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rosgraph_msgs.msg import Clock

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(150 + os.getpid() % 70))
    ns = f'/clocked{os.getpid()}'
    with node_factory(JobServer, 'job_server') as make:
        server = make('-r', f'__ns:={ns}', '-p', 'private_clock:=true')
        clocks = Node('clocks', context=server.context)
        executor = SingleThreadedExecutor(context=server.context)
        executor.add_node(server)
        executor.add_node(clocks)
        try:
            goal = RunJob.Goal(job='slotting', duration=0.3)
            assert server._on_goal(goal) == GoalResponse.ACCEPT
            run: Any = server._run
            assert run.private_clock

            def tick(sec: int, nanosec: int = 0) -> Any:
                msg = Clock()
                msg.clock.sec, msg.clock.nanosec = sec, nanosec
                return msg

            own = clocks.create_publisher(Clock, f'{ns}/clock', 10)
            other = clocks.create_publisher(Clock, '/clock', 10)
            end = time.monotonic() + 10.0
            while run.progress.machine_time == 0.0 and time.monotonic() < end:
                other.publish(tick(7))  # another machine's, further on
                own.publish(tick(2, 500_000_000))
                executor.spin_once(timeout_sec=0.05)
            for _ in range(20):  # the global clock keeps ticking: still not taken
                other.publish(tick(7))
                executor.spin_once(timeout_sec=0.01)
            assert run.progress.machine_time == 2.5
            assert server._machine_clock.topic_name == f'{ns}/clock'
        finally:
            server._run = None  # no runner was started
            executor.shutdown()
            clocks.destroy_node()
