"""The trajectory node in this process publishes the job's path on mill/planned_path once it
is loaded (nav_msgs/Path, transient local: a viewer that joins later gets it), again when a
parameter change loads another path, and the points are the path's own."""

from __future__ import annotations

import os

import pytest
from mill_common.in_process import node_factory, set_one
from mill_common.ros import LATCHED_QOS
from mill_common.tool_path import PLANNED_POINTS

from mill_common import topics


@pytest.fixture(autouse=True)
def _private_domain(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(170 + os.getpid() % 10))


def _spin_until(executor, predicate, steps: int = 1000) -> bool:
    for _ in range(steps):
        if predicate():
            return True
        executor.spin_once(timeout_sec=0.01)
    return predicate()


def _xyz(pose) -> tuple[float, float, float]:
    p = pose.pose.position
    return (p.x, p.y, p.z)


def test_the_job_path_is_latched_on_planned_path_and_follows_a_new_path() -> None:
    import rclpy
    from mill_trajectory.planned_path import job_path
    from mill_trajectory.trajectory_node import TrajectoryNode
    from nav_msgs.msg import Path
    from rclpy.executors import SingleThreadedExecutor

    with node_factory(TrajectoryNode, 'trajectory') as make:
        waypoints = '[0.0, 0.0, 0.0, 0.004, 0.002, 0.0]'
        node = make('-p', 'trajectory:=linear', '-p', f'linear.waypoints:={waypoints}')
        helper = rclpy.create_node('viewer', context=node.context)
        executor = SingleThreadedExecutor(context=node.context)
        executor.add_node(node)
        executor.add_node(helper)
        try:
            got: list[Path] = []
            helper.create_subscription(Path, topics.PLANNED_PATH, got.append, LATCHED_QOS)
            assert _spin_until(executor, lambda: len(got) == 1)
            path = job_path(node._schedule)
            msg = got[0]
            assert msg.header.frame_id == 'mill_base'
            assert len(msg.poses) == PLANNED_POINTS
            assert _xyz(msg.poses[0]) == path.sample(0.0).position
            end = path.end_time
            assert end == pytest.approx(2e-5**0.5 / 0.003, rel=1e-12)  # 4.47 mm at 3 mm/s
            assert _xyz(msg.poses[-1]) == path.sample(end).position == (0.004, 0.002, 0.0)
            middle = (PLANNED_POINTS - 1) // 2
            t = end * middle / (PLANNED_POINTS - 1)
            assert _xyz(msg.poses[middle]) == path.sample(t).position
            # Another path loaded: published again, its end where the new path ends.
            # `ros2 param load`: one parameter at a time, each loading the job anew; the
            # path goes out once, after the last
            waypoints = [0.0, 0.0, 0.0, 0.004, 0.002, 0.0, 0.004, 0.002, -0.001]
            for name in ('linear.feed_rate', 'settle_time', 'input_warn_time'):
                assert set_one(node, name, node.get_parameter(name).value).successful
            assert set_one(node, 'linear.waypoints', waypoints).successful
            assert _spin_until(executor, lambda: len(got) == 2)
            for _ in range(50):  # 0.5 s: no other
                executor.spin_once(timeout_sec=0.01)
            assert len(got) == 2
            new = job_path(node._schedule)
            assert new is not path
            assert _xyz(got[1].poses[-1]) == new.sample(new.end_time).position
            assert _xyz(got[1].poses[-1]) == pytest.approx((0.004, 0.002, -0.001), abs=1e-15)
        finally:
            executor.shutdown()
            helper.destroy_node()
