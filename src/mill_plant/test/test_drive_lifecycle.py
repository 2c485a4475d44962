"""The drive's lifecycle in one process: what a configure after a cleanup makes."""

from __future__ import annotations

import os

import pytest


@pytest.mark.parametrize('timing', ['lockstep', 'realtime'])
def test_a_configure_after_a_cleanup_takes_the_same_topics_again(monkeypatch, timing) -> None:
    import rclpy
    from mill_common.graph_owner import GidSubscription
    from mill_plant.plant_node import make_node
    from rclpy.parameter import Parameter

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(200 + os.getpid() % 30))
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = make_node(
            context=context,
            parameter_overrides=[
                Parameter('autostart', value=False),
                Parameter('timing', value=timing),
            ],
        )

        def made_now() -> tuple[int, int]:
            # Commands are taken with their publisher GID (mill_common.graph_owner).
            taking = [w for w in node.waitables if isinstance(w, GidSubscription)]
            return len(list(node.publishers)), len(list(node.subscriptions)) + len(taking)

        node.trigger_configure()
        made = made_now()
        node.trigger_cleanup()
        node.trigger_configure()
        # Commands taken twice, states sent by two writers: the first configure's topics
        # must be the ones taken again, not left beside new ones.
        assert made_now() == made
        assert made[1] >= 3  # a command subscription per axis at least
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
