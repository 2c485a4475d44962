"""The points the viewers draw: the planned path sampled evenly, the measured trace
decimated to its rate and bounded (mill_common.tool_path)."""

from __future__ import annotations

import math

import pytest
from mill_common.tool_path import PLANNED_HORIZON, TraceDecimator, planned_points


def test_the_planned_path_is_sampled_evenly_from_start_to_end() -> None:
    times: list[float] = []

    def line(t: float) -> tuple[float, float, float]:
        times.append(t)
        return (0.001 * t, -0.002 * t, 0.5)

    points = planned_points(line, 4.0, max_points=9)
    assert times == [0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0]
    assert points[0] == (0.0, 0.0, 0.5) and points[-1] == (0.004, -0.008, 0.5)
    assert planned_points(line, 0.0) == [(0.0, 0.0, 0.5)]
    times.clear()
    planned_points(line, math.inf, max_points=3)
    assert times == [0.0, PLANNED_HORIZON / 2, PLANNED_HORIZON]
    with pytest.raises(ValueError, match='at least 2'):
        planned_points(line, 1.0, max_points=1)


def _feed(trace: TraceDecimator, seconds: float, rate: int = 1000) -> int:
    """States of x, y, z at `rate` Hz for `seconds` (x = t, y = 2t, z = -t); points kept."""
    kept = 0
    for k in range(round(seconds * rate) + 1):
        ns = k * 1_000_000_000 // rate
        t = ns * 1e-9
        for axis, value in (('x', t), ('y', 2 * t), ('z', -t)):
            kept += trace.take(axis, ns, value)
    return kept


def test_the_trace_keeps_one_point_per_period_of_the_states_stamps() -> None:
    trace = TraceDecimator(('x', 'y', 'z'), 50_000_000, 1000)  # 20 Hz
    # 2 s of 1 kHz states: t = 0, 0.05, ..., 2.0 s (41 points), each once all three
    # axes of that sample are in.
    assert _feed(trace, 2.0) == 41
    stamps = [ns for ns, _ in trace.points]
    assert stamps == [k * 50_000_000 for k in range(41)]
    assert trace.points[-1][1] == pytest.approx((2.0, 4.0, -2.0))


def test_the_trace_is_bounded_and_skips_what_it_cannot_draw() -> None:
    trace = TraceDecimator(('x', 'y', 'z'), 50_000_000, 10)
    assert _feed(trace, 2.0) == 41
    assert len(trace.points) == 10
    assert trace.points[0][0] == 31 * 50_000_000  # the newest ten: t = 1.55 .. 2.0 s
    # a NaN position, an unknown axis: not taken
    assert not trace.take('x', 3_000_000_000, math.nan)
    assert not trace.take('w', 3_000_000_000, 1.0)
    assert trace.points[-1][0] == 2_000_000_000
    # a stamp before the last point's: a new run, a new trace
    assert trace.take('x', 0, 0.25)
    assert list(trace.points) == [(0, (0.25, 4.0, -2.0))]
    # axes stamped apart: the point is where the latest-stamped axis has been joined
    assert not trace.take('y', 60_000_000, 1.0) and not trace.take('z', 70_000_000, 1.0)
    assert trace.take('x', 80_000_000, 1.0)
    assert trace.points[-1] == (60_000_000, (1.0, 1.0, 1.0))


def test_no_point_before_every_axis_has_a_position() -> None:
    trace = TraceDecimator(('x', 'y', 'z'), 1, 5)
    assert not trace.take('x', 0, 1.0) and not trace.take('y', 0, 2.0)
    assert trace.take('z', 0, 3.0) and list(trace.points) == [(0, (1.0, 2.0, 3.0))]
    # a two-axis machine: the missing axis stands at 0
    two = TraceDecimator(('x', 'y'), 1, 5)
    assert not two.take('x', 0, 1.0) and two.take('y', 0, 2.0)
    assert list(two.points) == [(0, (1.0, 2.0, 0.0))]
