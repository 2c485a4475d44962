"""A feed override that changes keeps the planner's limits (mill_trajectory.override_limit)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from mill_trajectory.feed_override import TimeScaledPath
from mill_trajectory.gcode_program import GcodeTrajectory
from mill_trajectory.override_limit import FollowedOverride, OverrideLimit

T = 1e-3
V, A, J = 0.05, 0.5, 10.0  # the defaults: per axis [m/s, m/s², m/s³]
O_MAX = 2.0
# Corners, an arc and a climb at the machine's full feed (the planner slows them).
PART = """G21 G91
G1 X4 Y1 F3000
G2 X3 Y-3 R3
G1 Y-4 Z-1
G3 X-3 Y-3 I-3 J0
G1 X-4 Z1
"""
# Rounding: a and j are computed exactly at each sample; their differences over a sample
# are bounded by the next derivative's limit up to float rounding.
TOLERANCE = 1e-9


def _path(tmp: Path) -> GcodeTrajectory:
    part = tmp / 'part.ngc'
    part.write_text(PART)
    # Corners within 1 mm: the planner lets the path accelerate more than with 0.01 mm.
    values = {'file': str(part), 'tolerance': 1e-3}
    return GcodeTrajectory.from_parameters(values, override_max=O_MAX)


changes = st.lists(st.tuples(st.integers(0, 3500), st.floats(0.0, O_MAX)), min_size=1, max_size=12)


@settings(max_examples=25, deadline=None)
@given(changes=changes)
def test_any_override_sequence_keeps_velocity_acceleration_and_jerk(tmp_path_factory, changes):
    path = _path(tmp_path_factory.mktemp('part'))
    assert path.override_limit is not None
    scaled = TimeScaledPath(path, T, limit=path.override_limit)
    offered, at = 1.0, dict(changes)
    v, a, o = [], [], []
    for k in range(4000):
        offered = at.get(k, offered)
        s = scaled.sample(offered)
        v.append(s.velocity)
        a.append(s.acceleration)
        assert scaled.followed is not None
        o.append(scaled.followed.value)
    v, a = np.array(v), np.array(a)
    assert max(o) <= O_MAX * (1 + TOLERANCE) and min(o) >= -TOLERANCE
    assert np.abs(v).max() <= V * (1 + TOLERANCE)
    assert np.abs(a).max() <= A * (1 + TOLERANCE)
    assert np.abs(np.diff(v, axis=0)).max() / T <= A * (1 + TOLERANCE)
    assert np.abs(np.diff(a, axis=0)).max() / T <= J * (1 + TOLERANCE)


def test_without_the_limit_the_same_changes_break_the_limits(tmp_path) -> None:
    path = _path(tmp_path)  # the part above, the override stepping 0.3 <-> 2 every 0.15 s
    scaled = TimeScaledPath(path, T)
    v = np.array([scaled.sample(2.0 if (k // 150) % 2 else 0.3).velocity for k in range(3000)])
    assert np.abs(np.diff(v, axis=0)).max() / T > 10 * A


def test_the_override_reaches_what_is_offered_and_passes_no_target() -> None:
    limit = OverrideLimit.of((V,) * 3, (A,) * 3, (J,) * 3, O_MAX)
    assert limit is not None and 0 < limit.rate < 100 and 0 < limit.change < 1e4
    follow = FollowedOverride(limit)
    values = []
    for _ in range(5000):
        follow.step(0.4, T)
        values.append(follow.value)
    assert min(values) >= 0.4 - 1e-12 and values[-1] == 0.4
    rates = np.diff(values) / T
    assert np.abs(rates).max() <= limit.rate * (1 + TOLERANCE)
    assert np.abs(np.diff(rates)).max() / T <= limit.change * (1 + 1e-6)


def test_no_limit_without_acceleration_and_jerk_limits() -> None:
    inf = (float('inf'),) * 3
    assert OverrideLimit.of((V,) * 3, inf, inf, O_MAX) is None
