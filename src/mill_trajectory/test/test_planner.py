"""The feed planner never exceeds a per-axis limit and keeps corners within the tolerance."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from mill_trajectory.planner import ZERO_LENGTH, Limits, Piece, plan

coordinate = st.floats(-0.02, 0.02)
point = st.tuples(coordinate, coordinate, coordinate)
positive = st.floats(0.05, 20.0)


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    ab = b - a
    n = float(ab @ ab)
    f = 0.0 if n == 0.0 else min(max(float((p - a) @ ab) / n, 0.0), 1.0)
    return float(np.linalg.norm(p - (a + f * ab)))


# Chains that once ran the planner out of passes (a corner held long by its neighbour's
# transition; two overlapping transitions a fraction of a per cent over the jerk limit).
@example(
    points=[(0.0, 0.0, 0.0), (0.015625, 0.0, 0.0), (0.0, 0.0, 0.00390625), (-0.015625, 0.0, 0.0)],
    feeds=[0.125] * 5,
    velocity=(0.0625, 0.0625, 0.0625),
    acceleration=(1.0, 1.0, 1.0),
    jerk=(1.0, 1.0, 1.0),
    tolerance=1e-06,
    dwell=False,
)
@example(
    points=[(0.0, 0.0, 0.015625), (0.015625, 0.0, 0.0), (0.0, 0.0, 0.0)],
    feeds=[0.125] * 5,
    velocity=(0.03125, 0.0625, 0.0625),
    acceleration=(1.0, 1.0, 1.0),
    jerk=(59.0, 1.0, 3.0),
    tolerance=0.0008799284677263503,
    dwell=False,
)
@settings(max_examples=40, deadline=None)
@given(
    points=st.lists(point, min_size=2, max_size=6),
    feeds=st.lists(st.floats(0.001, 0.2), min_size=5, max_size=5),
    velocity=st.tuples(*[st.floats(0.005, 0.1)] * 3),
    acceleration=st.tuples(*[positive] * 3),
    jerk=st.tuples(*[st.floats(1.0, 500.0)] * 3),
    tolerance=st.floats(1e-6, 1e-3),
    dwell=st.booleans(),
)
def test_never_exceeds_a_limit(points, feeds, velocity, acceleration, jerk, tolerance, dwell):
    limits = Limits(velocity, acceleration, jerk, tolerance)
    pieces = [
        Piece(a, b, feeds[i % len(feeds)]) for i, (a, b) in enumerate(itertools.pairwise(points))
    ]
    if dwell and len(pieces) > 1:
        here = pieces[0].end
        pieces.insert(1, Piece(here, here, dwell=0.1, rest=True))
    path = plan(pieces, limits)
    assert math.isfinite(path.end_time)
    n = 4000
    h = 1e-6
    ts = np.linspace(-0.1, path.end_time + 0.1, n)
    corners = np.array(points)
    vmax, amax, jmax = (np.array(x) for x in (velocity, acceleration, jerk))
    # a move shorter than ZERO_LENGTH is no move: the ends agree to within it
    assert np.allclose(path.sample(-1.0).position, points[0], rtol=0.0, atol=ZERO_LENGTH)
    end = path.sample(path.end_time + 1.0).position
    assert np.allclose(end, points[-1], rtol=0.0, atol=ZERO_LENGTH * len(points))
    for t in ts:
        s = path.sample(float(t))
        v, a = np.array(s.velocity), np.array(s.acceleration)
        assert np.all(np.abs(v) <= vmax * (1 + 1e-9)), (t, v, vmax)
        assert np.all(np.abs(a) <= amax * (1 + 1e-9)), (t, a, amax)
        later = np.array(path.sample(float(t) + h).acceleration)
        assert np.all(np.abs(later - a) / h <= jmax * (1 + 1e-6) + 1e-6), (t, a, later)
        p = np.array(s.position)
        off = min(_segment_distance(p, corners[i], corners[i + 1]) for i in range(len(points) - 1))
        assert off <= tolerance * (1 + 1e-9) + 1e-15, (t, off, tolerance)
        # A feed is never exceeded beyond the faster of two neighbouring pieces.
        assert float(np.linalg.norm(v)) <= max(feeds) * (1 + 1e-9)


def test_velocity_and_acceleration_are_continuous_at_a_corner() -> None:
    limits = Limits((0.05,) * 3, (0.5,) * 3, (10.0,) * 3, 1e-5)
    path = plan(
        [Piece((0, 0, 0), (0.01, 0, 0), 0.01), Piece((0.01, 0, 0), (0.01, 0.01, 0), 0.01)], limits
    )
    ts = np.linspace(0.0, path.end_time, 200001)
    v = np.array([path.sample(float(t)).velocity for t in ts])
    a = np.array([path.sample(float(t)).acceleration for t in ts])
    dt = ts[1] - ts[0]
    assert np.abs(np.diff(v, axis=0)).max() <= 0.5 * dt * (1 + 1e-6)
    assert np.abs(np.diff(a, axis=0)).max() <= 10.0 * dt * (1 + 1e-6)
    # Feed reached between the corners: the corner slows only its neighbourhood.
    assert max(np.linalg.norm(v, axis=1)) == pytest.approx(0.01, rel=1e-12)


def test_without_acceleration_and_jerk_limits_the_velocity_steps() -> None:
    inf = math.inf
    limits = Limits((1.0,) * 3, (inf,) * 3, (inf,) * 3, 1e-5)
    path = plan(
        [Piece((0, 0, 0), (0.01, 0, 0), 0.01), Piece((0.01, 0, 0), (0.01, 0.01, 0), 0.02)], limits
    )
    assert path.end_time == 1.5
    assert path.sample(0.5).velocity == (0.01, 0.0, 0.0)
    assert path.sample(1.0).velocity == (0.0, 0.02, 0.0)
