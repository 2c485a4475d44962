"""The trajectory node's feed-override input (issue 4): it scales the path speed, and an
override outside its range or a NaN never reaches the reference: clamped or held, with a
WARN on /diagnostics."""

from __future__ import annotations

import math

import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from mill_common.ros import DATA_QOS, from_stamp, joint_state, to_stamp
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from mill_common import topics
from test.conftest import ros_node, spin_until

FEED = 0.003  # slotting: 3 mm/s along the first cut (+y)
TICK_NS = 10_000_000


@pytest.mark.system
def test_override_scales_the_speed_and_bad_values_are_clamped_or_held(start_node) -> None:
    trajectory = start_node(
        'mill_trajectory.trajectory_node',
        'trajectory',
        '-p',
        'trajectory:feed_override.enabled:=true',
    )
    refs: dict[int, float] = {}  # first point's stamp -> y velocity of the last point
    warnings: list[str] = []

    def on_reference(msg: JointTrajectory) -> None:
        refs[from_stamp(msg.header.stamp)] = msg.points[-1].velocities[1]

    def on_diagnostics(msg: DiagnosticArray) -> None:
        warnings.extend(s.message for s in msg.status if s.level == DiagnosticStatus.WARN)

    with ros_node('override_tester') as (node, executor):
        node.create_subscription(JointTrajectory, topics.REFERENCE, on_reference, DATA_QOS)
        node.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, on_diagnostics, 100)
        clock = node.create_publisher(Clock, topics.CLOCK, DATA_QOS)
        override = node.create_publisher(JointState, topics.FEED_OVERRIDE, 10)

        def matched() -> bool:
            return (
                clock.get_subscription_count() > 0
                and override.get_subscription_count() > 0
                and node.count_publishers(topics.REFERENCE) > 0
            )

        assert spin_until(executor, matched, 60), 'trajectory node never matched'
        spin_until(executor, lambda: False, 0.5)  # let discovery settle on its side too

        def tick(k: int, value: float | None) -> float:
            if value is not None:
                override.publish(joint_state(k * TICK_NS, ('feed_override',), (value,)))
                spin_until(executor, lambda: False, 0.3)
            clock.publish(Clock(clock=to_stamp(k * TICK_NS)))
            # the chunk of this tick starts where the previous one ended (the first: any)
            assert spin_until(
                executor,
                lambda: any(ns >= (k + 1) * TICK_NS for ns in refs) or k == 0 < len(refs),
            )
            return refs[max(refs)]

        tick(0, None)
        assert refs[max(refs)] == pytest.approx(FEED)  # no override yet: programmed feed
        assert tick(1, 0.5) == pytest.approx(0.5 * FEED)
        assert tick(2, 5.0) == pytest.approx(1.5 * FEED)  # clamped to feed_override.max
        assert tick(3, math.nan) == pytest.approx(1.5 * FEED)  # held
        assert spin_until(executor, lambda: len(warnings) >= 2)
        assert any('outside' in w for w in warnings) and any('non-finite' in w for w in warnings)
    assert trajectory.alive()
