"""The viewers' topics of one machine, in this process: the URDF on robot_description
(transient local, the job's travel as the joints' limits) and the measured tool trace on
mill/tool_trace (nav_msgs/Path, one point per 1/trace_rate of the states' stamps, bounded)."""

from __future__ import annotations

import os
from xml.etree import ElementTree

import pytest
from mill_common.in_process import node_factory
from mill_common.ros import LATCHED_QOS, joint_state
from mill_common.signals import AXES

from mill_common import topics


@pytest.fixture(autouse=True)
def _private_domain(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(160 + os.getpid() % 10))


def _spin_until(executor, predicate, steps: int = 2000) -> bool:
    for _ in range(steps):
        if predicate():
            return True
        executor.spin_once(timeout_sec=0.01)
    return predicate()


def _taken(view) -> set[int]:
    """The stamps of the newest state of each axis the view has taken."""
    return {view.trace._newest.get(a, (-1, 0.0))[0] for a in AXES}


def test_the_trace_is_the_states_at_the_trace_rate_and_the_urdf_is_latched() -> None:
    import rclpy
    from mill_bringup.machine_view import MachineView
    from nav_msgs.msg import Path
    from rclpy.executors import SingleThreadedExecutor
    from sensor_msgs.msg import JointState
    from std_msgs.msg import String

    with node_factory(MachineView, 'machine_view') as make:
        view = make('-p', 'trace_rate:=20.0', '-p', 'trace_length:=8')
        helper = rclpy.create_node('viewer', context=view.context)
        executor = SingleThreadedExecutor(context=view.context)
        executor.add_node(view)
        executor.add_node(helper)
        try:
            paths: list[Path] = []
            helper.create_subscription(Path, topics.TOOL_TRACE, paths.append, 100)
            states = {a: helper.create_publisher(JointState, topics.state(a), 10) for a in AXES}
            assert _spin_until(
                executor, lambda: all(view.count_publishers(topics.state(a)) for a in AXES)
            )
            assert _spin_until(executor, lambda: view.count_subscribers(topics.TOOL_TRACE) == 1)
            # 0.5 s of 1 kHz states: x = t, y = 2t, z = -t [mm]
            for k in range(501):
                ns = k * 1_000_000
                for a, scale in zip(AXES, (1.0, 2.0, -1.0), strict=True):
                    states[a].publish(joint_state(ns, [a], [scale * 1e-3 * k * 1e-3]))
                assert _spin_until(executor, lambda ns=ns: _taken(view) == {ns}), k
            assert _spin_until(executor, lambda: len(paths) == 11)
            # One Path per point kept (t = 0, 0.05, ..., 0.5 s), the newest 8 of them.
            assert [len(p.poses) for p in paths] == [1, 2, 3, 4, 5, 6, 7, 8, 8, 8, 8]
            last = paths[-1]
            assert last.header.frame_id == 'mill_base'
            stamps = [p.header.stamp.sec * 10**9 + p.header.stamp.nanosec for p in last.poses]
            assert stamps == [k * 50_000_000 for k in range(3, 11)]
            end = last.poses[-1].pose.position
            assert (end.x, end.y, end.z) == pytest.approx((0.5e-3, 1.0e-3, -0.5e-3), abs=1e-15)
            # robot_description, heard by a subscriber that joins late
            urdf: list[String] = []
            helper.create_subscription(String, topics.ROBOT_DESCRIPTION, urdf.append, LATCHED_QOS)
            assert _spin_until(executor, lambda: len(urdf) == 1)
            robot = ElementTree.fromstring(urdf[0].data)
            assert [j.get('name') for j in robot.iter('joint')] == list(AXES)
        finally:
            executor.shutdown()
            helper.destroy_node()


def test_the_urdf_of_a_job_has_its_travel_and_its_drive_limits() -> None:
    from mill_bringup.job_config import build
    from mill_bringup.machine_model import robot_description
    from mill_bringup.scenario import load

    scen = load('slotting')
    scen.add_override('trajectory.travel.min=[-0.2, -0.25, -0.05]')
    scen.add_override('trajectory.travel.max=[0.15, 0.3, 0.01]')
    scen.add_override('plant.speed_limit=0.125')
    config = build(scen)
    travel = config.values(config.trajectory or '')
    drive = config.values(config.plant or '')
    robot = ElementTree.fromstring(robot_description(config))
    limits = {j.get('name'): j.find('limit') for j in robot.iter('joint')}
    assert list(limits) == list(AXES)
    for i, axis in enumerate(AXES):
        limit = limits[axis]
        assert limit is not None
        assert float(limit.get('lower', 'nan')) == travel['travel.min'][i]
        assert float(limit.get('upper', 'nan')) == travel['travel.max'][i]
        assert float(limit.get('velocity', 'nan')) == drive['speed_limit']
        assert float(limit.get('effort', 'nan')) == drive['max_torque'][i]
    assert (travel['travel.min'], drive['speed_limit']) == ([-0.2, -0.25, -0.05], 0.125)
