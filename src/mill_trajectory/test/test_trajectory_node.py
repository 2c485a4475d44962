"""The trajectory node in this process: ~/resume and ~/feed_hold, and the program's messages
and pauses in its log and on /diagnostics (issues 33 and 34)."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from mill_common.in_process import node_factory

PART = """G21 G90 G17
(MSG, first cut)
G1 X10 F600
M0
G1 Y10
M30
"""


@pytest.fixture
def trajectory(monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[..., Any]]:
    """trajectory(*ros_args) -> a TrajectoryNode `trajectory` in a context of its own."""
    from mill_trajectory.trajectory_node import TrajectoryNode

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(150 + os.getpid() % 10))
    with node_factory(TrajectoryNode, 'trajectory') as make:
        yield make


class Operator:
    """A node of its own that calls the trajectory's services and hears /diagnostics."""

    def __init__(self, node: Any) -> None:
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        from std_srvs.srv import Trigger

        self.node = node
        self.probe = Node('operator', context=node.context)
        self.executor = SingleThreadedExecutor(context=node.context)
        for n in (node, self.probe):
            self.executor.add_node(n)
        self.statuses: list[dict[str, str]] = []
        self.probe.create_subscription(DiagnosticArray, '/diagnostics', self._heard, 100)
        self.clients = {
            name: self.probe.create_client(Trigger, f'/trajectory/{name}')
            for name in ('resume', 'feed_hold')
        }
        self.request = Trigger.Request

    def _heard(self, msg: Any) -> None:
        for s in msg.status:
            self.statuses.append({'message': s.message, **{kv.key: kv.value for kv in s.values}})

    def call(self, name: str) -> tuple[bool, str]:
        client = self.clients[name]
        assert client.wait_for_service(timeout_sec=10)
        future = client.call_async(self.request())
        self.executor.spin_until_future_complete(future, timeout_sec=10)
        result = future.result()
        return bool(result.success), str(result.message)

    def ticks(self, first: int, count: int) -> None:
        """The plant's /clock ticks of samples first .. first + count − 1, 1 ms apart."""
        from builtin_interfaces.msg import Time
        from rosgraph_msgs.msg import Clock

        for k in range(first, first + count):
            ns = k * 1_000_000
            self.node._on_clock(Clock(clock=Time(sec=ns // 10**9, nanosec=ns % 10**9)))

    def settle(self, events: int) -> None:
        """Spin until `events` statuses with an event arrived (or 10 s of tries)."""
        for _ in range(200):
            self.executor.spin_once(timeout_sec=0.05)
            if len([s for s in self.statuses if 'event' in s]) >= events:
                return

    def close(self) -> None:
        self.executor.shutdown()
        self.probe.destroy_node()


def test_a_pause_holds_until_resume_and_messages_reach_the_operator(
    trajectory: Callable[..., Any], tmp_path: Path
) -> None:
    part = tmp_path / 'part.ngc'
    part.write_text(PART)
    node = trajectory('-p', 'trajectory:=gcode', '-p', f'gcode.file:={part}')
    op = Operator(node)
    try:
        assert op.call('resume') == (False, 'nothing to resume: no pause and no feed hold')
        op.ticks(0, 2000)  # the pause comes at about 1.1 s
        assert node.holds.state == 'paused'
        ok, said = op.call('feed_hold')
        assert not ok and said.startswith(f'paused at {part}:4:1 (M0: program stop)')
        assert '\n' not in said
        assert op.call('resume') == (
            True,
            f'resumed after the pause at {part}:4:1 (M0: program stop)',
        )
        op.ticks(2000, 100)
        assert node.holds.state == 'running'
        op.settle(5)
    finally:
        op.close()
    told = [
        (s['event'], s.get('event_where', ''), s['message']) for s in op.statuses if 'event' in s
    ]
    assert told[0] == ('resume', '', 'nothing to resume: no pause and no feed hold')
    assert told[1] == ('message', f'{part}:2:1', f'{part}:2:1: MSG: first cut')
    kind, where, message = told[2]
    assert (kind, where) == ('paused', f'{part}:4:1')
    assert message.endswith("call the trajectory's ~/resume (std_srvs/Trigger) to go on")
    assert [t[0] for t in told[3:5]] == ['feed_hold', 'resume']
    # While paused the path time stands still; the status says so on the clock's seconds.
    held = [s for s in op.statuses if s.get('hold') == 'paused' and 'event' not in s]
    assert held and held[0]['message'] == 'job paused'
    first_cut = next(s for s in op.statuses if s.get('event') == 'message')
    assert first_cut['event_channel'] == 'MSG' and 0.0 < float(first_cut['event_time_s']) < 0.1


def test_feed_hold_is_refused_in_one_line_where_the_plan_has_no_room(
    trajectory: Callable[..., Any], tmp_path: Path
) -> None:
    part = tmp_path / 'part.ngc'
    part.write_text(PART)
    node = trajectory('-p', 'trajectory:=gcode', '-p', f'gcode.file:={part}')
    op = Operator(node)
    try:
        ok, said = op.call('feed_hold')
    finally:
        op.close()
    assert not ok and said.startswith('feed hold needs feed_override.enabled') and '\n' not in said
