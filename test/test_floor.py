"""The empty-callback floor of the benchmark (mill_bench.floor) runs and leaves nothing.

Its figure is a speed and is measured by `benchmark`, not here; this test checks that the
eight processes step together for the number of steps asked, report, and all end.
"""

from __future__ import annotations

import math

import pytest

from mill_bench import floor
from test.conftest import _left_in_domain


@pytest.mark.system
@pytest.mark.parametrize('listener', [False, True])
def test_the_empty_graph_steps_and_every_process_ends(ros_env, listener: bool) -> None:
    result = floor.measure(500, ros_env, listener=listener)
    assert result['steps_per_second'] > 0 and math.isfinite(result['steps_per_second'])
    assert result['plant_cpu_ms'] > 0
    # the CPU of every process over the timed steps: the plant's share and the others'
    used = result['cpu_ms_per_step_by_process']
    assert sorted(used) == sorted((*floor.ROLES, *(['listener'] if listener else [])))
    assert result['cpu_ms_per_step'] == pytest.approx(sum(used.values()))
    assert result['cpu_ms_per_step'] > used['plant'] > 0
    # this test's processes only (its domain): the other variant may run beside it (xdist)
    left = [
        cmd for _pid, cmd in _left_in_domain(ros_env['ROS_DOMAIN_ID']) if 'mill_bench.floor' in cmd
    ]
    assert left == [], left
