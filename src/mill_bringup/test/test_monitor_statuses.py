"""The monitor keeps the /diagnostics statuses of its own machine as Status values (not the
rclpy arrays: 6 kB each): what status(), statuses() and problems() read of them."""

from __future__ import annotations

import os
import time
from typing import Any


def test_the_statuses_of_its_machine_in_order_and_the_newest_by_name(monkeypatch) -> None:
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
    from mill_bringup.monitor import Monitor
    from rclpy.executors import SingleThreadedExecutor

    from mill_common import topics

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(120 + os.getpid() % 30))
    rclpy.init()
    try:
        monitor = Monitor({}, namespace='/m1')
        node = rclpy.create_node('plant', namespace='/m1')
        pub = node.create_publisher(DiagnosticArray, topics.DIAGNOSTICS, 10)
        executor = SingleThreadedExecutor()
        for n in (monitor, node):
            executor.add_node(n)

        def status(name: str, level: bytes, message: str, hw: str, **values: str) -> Any:
            kv = [KeyValue(key=k, value=v) for k, v in values.items()]
            return DiagnosticStatus(
                name=name, level=level, message=message, hardware_id=hw, values=kv
            )

        ok, warn, err = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR
        sent = [
            [status('/m1/plant: drive', ok, 'running', '/m1', step='1')],
            [
                status('/m2/plant: drive', err, 'tripped', '/m2', step='9'),  # another machine
                status('/m1/x_controller: inputs', warn, 'late', '/m1'),
            ],
            [status('/m1/plant: drive', err, 'tripped', '/m1', step='2')],
            [status('/m1/x_controller: inputs', warn, 'late', '/m1')],  # told twice
        ]
        deadline = time.monotonic() + 30
        while pub.get_subscription_count() < 1 and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        for stamp, statuses in enumerate(sent, 1):
            array = DiagnosticArray(status=statuses)
            array.header.stamp.sec = stamp
            pub.publish(array)
        while len(monitor.statuses()) < 4 and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        heard = monitor.statuses()
        assert [(s.stamp_ns, s.name, s.level) for s in heard] == [
            (1_000_000_000, '/m1/plant: drive', 0),
            (2_000_000_000, '/m1/x_controller: inputs', 1),
            (3_000_000_000, '/m1/plant: drive', 2),
            (4_000_000_000, '/m1/x_controller: inputs', 1),
        ]
        assert heard[2].values == {'step': '2'}
        assert monitor.status('plant: drive') == {'step': '2', 'message': 'tripped', 'level': '2'}
        assert monitor.status('plant: spindle') is None
        assert monitor.problems() == ['/m1/x_controller: inputs: late', '/m1/plant: drive: tripped']
        for n in (monitor, node):
            n.destroy_node()
    finally:
        rclpy.try_shutdown()
