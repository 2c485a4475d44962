"""`joint_states`: every axis in one JointState, decimated to at most `joint_states_rate`."""

from __future__ import annotations

import itertools
import math
import os

import pytest
from mill_plant.joint_states import JointStates, decimation

T_NS = 1_000_000  # 1 ms


@pytest.mark.parametrize(
    ('rate', 'period', 'every'),
    [(100.0, 0.001, 10), (50.0, 0.001, 20), (30.0, 0.001, 34), (100.0, 0.004, 3), (100.0, 0.02, 1)],
)
def test_the_decimation_keeps_the_rate_at_or_below_the_parameter(rate, period, every) -> None:
    assert decimation(rate, period) == every
    assert 1.0 / (every * period) <= rate + 1e-9
    assert every == 1 or 1.0 / ((every - 1) * period) > rate  # the fewest that do
    assert decimation(0.0, period) == 0


def test_every_nth_new_sample_gives_the_whole_machine() -> None:
    joints = JointStates(['x', 'y', 'z'], 250.0, 0.001)  # every 4th sample
    out = []
    for k in range(12):
        x = [0.001 * k, -0.002 * k, 0.0]
        got = joints.sample(k * T_NS, x, [1.0, math.nan, 0.5])
        again = joints.sample(k * T_NS, x, [1.0, math.nan, 0.5])  # lockstep offers it again
        assert again is None
        if got is not None:
            out.append((k, got))
    assert [k for k, _ in out] == [0, 4, 8]
    _, first = out[0]
    assert first.names == ('x', 'y', 'z')
    assert all(math.isnan(v) for v in first.velocity)  # no speed before two samples
    k, later = out[1]
    assert later.position == [0.004, -0.008, 0.0]
    assert later.velocity == pytest.approx([1.0, -2.0, 0.0])  # m/s, over the last period
    assert later.effort[0] == 1.0 and math.isnan(later.effort[1])


def test_the_drive_publishes_joint_states_at_the_decimated_rate(monkeypatch) -> None:
    """In one process: a realtime drive at 1 kHz with joint_states_rate 100 Hz publishes one
    sensor_msgs/JointState with x, y, z every 10th state it publishes."""
    import rclpy
    from mill_plant.plant_node import make_node
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.parameter import Parameter
    from sensor_msgs.msg import JointState

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(150 + os.getpid() % 30))
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = make_node(
            context=context,
            parameter_overrides=[
                Parameter('timing', value='realtime'),
                Parameter('sample_period', value=0.001),
                Parameter('joint_states_rate', value=100.0),
            ],
        )
        reader = rclpy.create_node('reader', context=context)
        joints: list[JointState] = []
        states: list[int] = []
        reader.create_subscription(JointState, 'joint_states', joints.append, 1000)
        reader.create_subscription(
            JointState,
            'mill/x/state',
            lambda m: states.append(m.header.stamp.sec * 10**9 + m.header.stamp.nanosec),
            1000,
        )
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        executor.add_node(reader)
        for _ in range(20000):
            executor.spin_once(timeout_sec=0.01)
            if len(joints) >= 6:
                break
        assert len(joints) >= 6
        for msg in joints:
            assert list(msg.name) == ['x', 'y', 'z']
            assert len(msg.position) == len(msg.velocity) == len(msg.effort) == 3
        # Decimated by count, not by the clock: ten states from one to the next.
        stamps = [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for m in joints]
        heard = [s for s in stamps if states and states[0] <= s <= states[-1]]
        assert len(heard) >= 3
        gaps = [states.index(b) - states.index(a) for a, b in itertools.pairwise(heard)]
        assert gaps == [10] * len(gaps)
        executor.shutdown()
        reader.destroy_node()
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
