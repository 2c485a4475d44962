"""`benchmark --realtime` measures the hardware case and its floor (mill_bench.realtime_sweep).

One rate in one layout, briefly: the drive in its own process against the single layout's
container, then against the echo node. Its figures are speeds, measured by `benchmark`,
not judged here; this test checks that both cases run and report what the table needs:
the drive's own figures on every axis, its ticks, the hops the listener timed (the floor
has no observer) and the CPU per tick.
"""

from __future__ import annotations

import math

import pytest
from mill_bench.realtime_sweep import sweep

from test.conftest import EXTENDED

# Timing under load is what it checks: alone on the machine (scripts/test.sh, serial).
pytestmark = pytest.mark.serial

AXES = ('x', 'y', 'z')


@pytest.mark.system
@EXTENDED  # checks the benchmark's sweep itself; realtime jobs run in CI elsewhere
def test_the_hardware_case_and_its_floor_at_one_rate(ros_env: dict[str, str]) -> None:
    points = sweep('slotting', ['single'], [250.0], 1.5, ros_env['ROS_DOMAIN_ID'], lambda _: None)
    assert [(p.case, p.rate_hz) for p in points] == [('floor', 250.0), ('single', 250.0)]
    floor, single = points
    for p in points:
        assert not any(n.startswith('the run failed') for n in p.notes), p.notes
        assert set(p.drive) == set(AXES)
        assert 0.0 <= p.late_fraction < 1.0 and p.latency_median_ms > 0.0
        assert p.ticks >= 250, p  # the drive's active ticks: at least 1 s at 250 Hz
        assert math.isfinite(p.cpu_drive_ms) and math.isfinite(p.cpu_rest_ms)
    assert set(floor.hops['x']) == {'state', 'loop'}
    assert set(single.hops['x']) == {'state', 'observer', 'controller', 'loop'}
