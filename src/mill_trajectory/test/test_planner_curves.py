"""On curves the planner holds the speed the limits allow, within the limits and tolerance.

The allowed speed of a circle of radius r is computed here from the limits alone:
min(F, v_max, √(a_max·r), (j_max·r²)^⅓) (centripetal acceleration u²/r and jerk u³/r² on an
axis at the quarter points). Three turns are programmed and the middle one measured: the
first and last also speed up from and slow down to the corner with the approach move.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from mill_trajectory.feed_report import block_feeds, pieces_by_block
from mill_trajectory.gcode import parse_program
from mill_trajectory.planner import Limits, Piece, plan

V, A, J, TOL = 0.05, 0.5, 10.0, 1e-5
LIMITS = Limits((V,) * 3, (A,) * 3, (J,) * 3, TOL)


def _allowed(r: float, feed: float) -> float:
    return min(feed, V, math.sqrt(A * r), (J * r * r) ** (1.0 / 3.0))


def _turns(radius_mm: float, feed_mm_s: float) -> str:
    r, f = radius_mm, 60.0 * feed_mm_s
    arc = f'G3 X{r:g} Y0 I{-r:g} J0'
    return f'G21 G90 G17\nG0 X{r:g} Y0\nG1 Y0 F{f:g}\n{arc}\n{arc}\n{arc}\nM30\n'


def _check_limits_and_path(path, on_path) -> None:
    """Dense samples: per-axis velocity, acceleration, jerk within the limits; every point
    within TOL of the programmed path (on_path: distance of points to it)."""
    dt = 2e-4
    ts = np.arange(0.0, path.end_time + dt, dt)
    s = [path.sample(float(t)) for t in ts]
    v = np.array([x.velocity for x in s])
    a = np.array([x.acceleration for x in s])
    p = np.array([x.position for x in s])
    assert np.abs(v).max() <= V * (1 + 1e-9)
    assert np.abs(a).max() <= A * (1 + 1e-9)
    assert np.abs(np.diff(a, axis=0)).max() / dt <= J * (1 + 1e-6)
    assert on_path(p).max() <= TOL * (1 + 1e-9)


@pytest.mark.parametrize('radius', [0.25, 1.0, 5.0, 50.0])
@pytest.mark.parametrize('feed', [10.0, 50.0])
def test_a_circle_runs_at_the_speed_the_limits_allow(radius: float, feed: float) -> None:
    moves = parse_program(_turns(radius, feed), 'circle.ngc', (0.0, 0.0, 0.0))
    pieces, blocks = pieces_by_block(moves, TOL)
    path = plan(pieces, LIMITS)
    arcs = [f for f in block_feeds(moves, pieces, blocks, path) if f.kind == 'arc']
    allowed = _allowed(radius * 1e-3, feed * 1e-3)
    assert arcs[1].mean >= 0.95 * allowed, (arcs[1].mean / allowed, allowed)
    assert arcs[1].peak <= allowed * (1 + 1e-9) or arcs[1].peak <= feed * 1e-3 * (1 + 1e-9)
    if radius <= 5.0:  # the largest takes long to sample densely
        r = radius * 1e-3
        _check_limits_and_path(
            path,
            lambda p: np.minimum(
                np.abs(np.hypot(p[:, 0], p[:, 1]) - r),
                np.hypot(p[:, 1], p[:, 0] - np.clip(p[:, 0], 0.0, r)),  # the approach, y = 0
            ),
        )


def test_a_fine_polyline_circle_runs_at_the_speed_the_limits_allow() -> None:
    # A CAM-style circle of 0.05 mm chords (r 2 mm: 251 chords a turn), three turns.
    r, feed = 2e-3, 0.05
    count = 251
    angles = np.linspace(0.0, 6.0 * np.pi, 3 * count + 1)
    points = [(r * math.cos(t), r * math.sin(t), 0.0) for t in angles]
    pieces = [Piece(a, b, feed) for a, b in itertools.pairwise(points)]
    path = plan(pieces, LIMITS)
    time, _ = path.piece_times(len(pieces))
    turn = slice(count, 2 * count)
    length = sum(math.dist(p.start, p.end) for p in pieces[turn])
    mean = length / float(time[turn].sum())
    allowed = _allowed(r, feed)
    assert mean >= 0.95 * allowed, (mean / allowed, allowed)
    corners = np.array(points)

    def off(p: np.ndarray) -> np.ndarray:  # distance to the polyline (its chords)
        a, b = corners[:-1], corners[1:]
        ab = b - a
        out = np.empty(len(p))
        for i, q in enumerate(p):
            f = np.clip(np.einsum('ij,ij->i', q - a, ab) / np.einsum('ij,ij->i', ab, ab), 0, 1)
            out[i] = np.linalg.norm(q - a - f[:, None] * ab, axis=1).min()
        return out

    _check_limits_and_path(path, off)


def test_the_first_chord_after_a_sharp_corner_does_not_crawl() -> None:
    # One turn of r 50 mm at 50 mm/s right after the approach's 90 degree corner: the arc's
    # first chord (1 mm) is slow at its start only. It used to run whole at the corner's
    # 1.85 mm/s (0.54 s for 1 mm, the turn at 91 % of F); cut at its corner end, the rest
    # ramps on into the curve.
    r, feed = 50.0, 50.0
    text = f'G21 G90 G17\nG0 X{r:g} Y0\nG3 X{r:g} Y0 I{-r:g} J0 F{60 * feed:g}\nM30\n'
    moves = parse_program(text, 'circle.ngc', (0.0, 0.0, 0.0))
    pieces, blocks = pieces_by_block(moves, TOL)
    path = plan(pieces, LIMITS)
    (arc,) = [f for f in block_feeds(moves, pieces, blocks, path) if f.kind == 'arc']
    assert arc.mean >= 0.95 * feed * 1e-3, arc.mean
    starts = path.piece_starts(pieces)
    first = next(k for k, b in enumerate(blocks) if moves[b].kind == 'arc')
    assert starts[first + 1] - starts[first] < 0.2  # the first chord, 1 mm
    # Within the limits around the corner (the first 0.6 s of the arc) and on the path.
    ts = np.arange(starts[first] - 0.2, starts[first] + 0.6, 2e-4)
    s = [path.sample(float(t)) for t in ts]
    v = np.array([x.velocity for x in s])
    a = np.array([x.acceleration for x in s])
    p = np.array([x.position for x in s])
    assert np.abs(v).max() <= V * (1 + 1e-9) and np.abs(a).max() <= A * (1 + 1e-9)
    assert np.abs(np.diff(a, axis=0)).max() / 2e-4 <= J * (1 + 1e-6)
    rm = r * 1e-3
    off = np.minimum(
        np.abs(np.hypot(p[:, 0] - 0.0, p[:, 1]) - rm),
        np.hypot(p[:, 1], p[:, 0] - np.clip(p[:, 0], 0.0, rm)),
    )
    assert off.max() <= TOL * (1 + 1e-9)
