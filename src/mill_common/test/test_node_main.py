"""The shared node entry point (mill_common.node_main): how a node process ends."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest

# A node that asks to end at once and whose destroy_node never returns, as an observer's
# once did in CI inside rclpy; the limit is shortened so that the test waits little.
HANGING_NODE = textwrap.dedent(
    """
    import time
    from mill_common import node_main
    from rclpy.node import Node

    node_main.TEARDOWN_LIMIT = {limit}

    class Stuck(Node):
        def __init__(self):
            super().__init__('stuck')
            self.create_timer(0.01, lambda: node_main.request_exit(self, 0, 'done'))

        def destroy_node(self):
            while True:
                {body}

    node_main.run_nodes([('', Stuck)], 'stuck', ['stuck'], own_process=True)
    """
)


@pytest.mark.parametrize('body', ['pass', 'time.sleep(60)'], ids=['python_loop', 'sleep_in_c'])
def test_a_teardown_that_hangs_ends_the_process_with_its_stacks(body: str) -> None:
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    env['ROS_DOMAIN_ID'] = str(101 + os.getpid() % 49)
    script = HANGING_NODE.format(limit=2.0, body=body)
    done = subprocess.run(
        [sys.executable, '-c', script], env=env, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 1, done.stderr
    assert 'Timeout (0:00:02)!' in done.stderr and 'in destroy_node' in done.stderr, done.stderr
