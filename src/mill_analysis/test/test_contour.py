"""The contour error: the distance to the programmed path (known geometry, against a
brute-force distance to every segment, and to the bit against the k-d tree search it
replaced), not the time-matched tracking error."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from mill_analysis.contour import _point_segment, distance_to_path
from mill_analysis.metrics import contour_error, summarize, summarize_contour
from mill_analysis.record import RunRecord
from mill_analysis.summary import axis_summary

from mill_analysis import contour


def brute_force(path: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The distance from each point to every segment of the path, the smallest."""
    a, v = path[:-1], np.diff(path, axis=0)
    p = points[:, None, :]
    vv = np.maximum(np.einsum('ij,ij->i', v, v), 1e-300)
    s = np.clip(np.einsum('mij,ij->mi', p - a, v) / vv, 0, 1)
    return np.linalg.norm(p - (a + s[..., None] * v), axis=2).min(axis=1)


@pytest.mark.parametrize('vertices', [2, 1001])
def test_a_point_off_a_straight_line_by_d_is_d_away(vertices: int) -> None:
    x = np.linspace(0.0, 1.0, vertices)
    path = np.column_stack([x, 0 * x])
    points = np.array([[0.3, 0.002], [0.77, -0.05], [0.5, 0.0], [1.2, 0.1], [-0.3, -0.4]])
    d, near = distance_to_path(path, points)
    np.testing.assert_allclose(d, [0.002, 0.05, 0.0, math.hypot(0.2, 0.1), 0.5], atol=1e-15)
    np.testing.assert_allclose(near, [[0.3, 0], [0.77, 0], [0.5, 0], [1, 0], [0, 0]], atol=1e-15)


def test_a_point_off_an_arc() -> None:
    r, n = 0.02, 2000
    theta = np.linspace(0, math.pi, n)
    path = r * np.column_stack([np.cos(theta), np.sin(theta)])
    rng = np.random.default_rng(3)
    phi = rng.uniform(0.1, math.pi - 0.1, 500)
    off = rng.uniform(-1e-4, 1e-4, 500)
    points = (r + off)[:, None] * np.column_stack([np.cos(phi), np.sin(phi)])
    d, near = distance_to_path(path, points)
    sagitta = r * (1 - math.cos(math.pi / (n - 1) / 2))  # chord to arc, 1.2 nm
    assert np.max(np.abs(d - np.abs(off))) <= sagitta
    np.testing.assert_allclose(np.linalg.norm(points - near, axis=1), d, rtol=1e-12)


def test_at_a_corner_the_nearest_segment_counts() -> None:
    path = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    points = np.array(
        [
            [0.9, 0.05],  # inside the corner, nearer the first leg (0.05) than the second (0.1)
            [1.1, 0.5],  # off the second leg
            [1.1, -0.1],  # outside the corner: its vertex is nearest
            [0.95, 0.97],  # near the end of the second leg
        ]
    )
    d, near = distance_to_path(path, points)
    np.testing.assert_allclose(d, [0.05, 0.1, math.hypot(0.1, 0.1), 0.05], atol=1e-15)
    np.testing.assert_allclose(near, [[0.9, 0], [1, 0.5], [1, 0], [1, 0.97]], atol=1e-15)


def random_walk(rng: np.random.Generator, n: int = 2000) -> tuple[np.ndarray, np.ndarray]:
    """A random walk with steps from 1 nm to 1 mm, repeated vertices, crossing itself (many
    samples near some points, segments of very different lengths), and points near and far."""
    steps = rng.normal(size=(n, 3)) * 10.0 ** rng.uniform(-9, -3, (n, 1))
    steps[rng.random(n) < 0.05] = 0.0
    path = np.cumsum(steps, axis=0)
    lo, hi = path.min(axis=0), path.max(axis=0)
    points = np.vstack(
        [
            rng.uniform(lo, hi, (n // 4, 3)),
            path[rng.integers(0, n, n // 4)] + rng.normal(scale=1e-6, size=(n // 4, 3)),
        ]
    )
    return path, points


@pytest.mark.parametrize(('fanout', 'max_pairs'), [(4, 1 << 20), (16, 1 << 20), (2, 1)])
def test_equals_the_distance_to_every_segment(monkeypatch, fanout: int, max_pairs: int) -> None:
    monkeypatch.setattr(contour, 'FANOUT', fanout)
    monkeypatch.setattr(contour, 'MAX_PAIRS', max_pairs)  # 1: every block split to one point
    path, points = random_walk(np.random.default_rng(7))
    d, near = distance_to_path(path, points)
    np.testing.assert_allclose(d, brute_force(path, points), rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(points - near, axis=1), d, rtol=1e-9, atol=1e-15)


def kdtree_distance(path: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """distance_to_path as it was until it dropped scipy (a k-d tree over points spaced at
    most h along the path gives each point's nearest sample at d0; every segment with a
    sample within d0 + h/2 is measured): the reference its answers must equal to the bit."""
    from scipy.spatial import cKDTree

    path = np.asarray(path, dtype=float)
    path = path[np.isfinite(path).all(axis=1)]
    keep = np.ones(len(path), dtype=bool)
    keep[1:] = np.any(path[1:] != path[:-1], axis=1)
    path = path[keep]
    if len(path) == 1:
        near = np.where(np.isfinite(points).all(axis=1)[:, None], path[0], np.nan)
        return np.linalg.norm(points - near, axis=1), near
    start, vec = path[:-1], np.diff(path, axis=0)
    length = np.linalg.norm(vec, axis=1)
    h = max(float(length.sum()) / 400_000, float(np.median(length)))
    pieces = np.maximum(1, np.ceil(length / h)).astype(int)
    spacing = float(np.max(length / pieces))
    seg = np.repeat(np.arange(len(start)), pieces)
    frac = (np.arange(seg.size) - np.repeat(np.cumsum(pieces) - pieces, pieces)) / pieces[seg]
    samples = np.vstack([start[seg] + frac[:, None] * vec[seg], path[-1:]])
    seg = np.append(seg, len(start) - 1)
    tree = cKDTree(samples)
    distance = np.full(len(points), np.nan)
    nearest = np.full(points.shape, np.nan)
    ok = np.flatnonzero(np.isfinite(points).all(axis=1))
    if ok.size == 0:
        return distance, nearest
    pts = points[ok]
    k = min(16, len(samples))
    dist, idx = tree.query(pts, k=k)
    dist, idx = dist.reshape(len(pts), k), idx.reshape(len(pts), k)
    reach = dist[:, 0] + 0.5 * spacing * (1 + 1e-9) + 1e-15
    covered = (dist[:, -1] > reach) | (k == len(samples))
    within = (dist <= reach[:, None]) & covered[:, None]
    rows, cand = np.nonzero(within)[0], idx[within]
    wide = np.flatnonzero(~covered)
    if wide.size:
        balls = tree.query_ball_point(pts[wide], reach[wide])
        rows = np.concatenate([rows, np.repeat(wide, [len(b) for b in balls])])
        cand = np.concatenate([cand, *[np.asarray(b, dtype=int) for b in balls]])
    segs = np.concatenate([seg[cand], np.maximum(seg[cand] - 1, 0)])
    rows = np.concatenate([rows, rows])
    d, q = _point_segment(pts[rows], start[segs], vec[segs])
    order = np.lexsort((d, rows))
    first = order[np.flatnonzero(np.diff(rows[order], prepend=-1))]
    distance[ok[rows[first]]] = d[first]
    nearest[ok[rows[first]]] = q[first]
    return distance, nearest


def arc_and_slot_paths(rng: np.random.Generator) -> list[tuple[np.ndarray, np.ndarray]]:
    """Paths as a job samples them, with measured positions around: an arc (outside it, a
    vertex is the nearest point), a slot cut back and forth at six depths, a corner."""
    out = []
    theta = np.linspace(0.0, 1.5 * math.pi, 3000)
    arc = 0.02 * np.column_stack([np.cos(theta), np.sin(theta), 0 * theta])
    out.append((arc, arc[rng.integers(0, 3000, 3000)] + rng.normal(scale=2e-5, size=(3000, 3))))
    out.append(slot(rng, [-0.001, -0.002, -0.003, -0.004, -0.005, -0.006]))
    corner = np.vstack(
        [np.linspace([0, 0, 0], [0.01, 0, 0], 500), np.linspace([0.01, 0, 0], [0.01, 0.01, 0], 500)]
    )
    out.append((corner, corner + rng.normal(scale=3e-4, size=corner.shape)))
    out.append(random_walk(rng))
    return out


def slot(rng: np.random.Generator, depths: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """A wavy slot 50 mm long cut back and forth, one pass at each depth [m], 2000 vertices a
    pass, and measured positions 10 µm off."""
    y = np.concatenate([np.linspace(0, -0.05, 2000), np.linspace(-0.05, 0, 2000)] * 3)
    path = np.column_stack(
        [0.001 * np.sin(40 * y), y[: 2000 * len(depths)], np.repeat(depths, 2000)]
    )
    return path, path + rng.normal(scale=1e-5, size=path.shape)


@pytest.mark.parametrize('seed', [1, 2, 3])
def test_the_same_bits_as_the_k_d_tree_on_random_paths(seed: int) -> None:
    for path, points in arc_and_slot_paths(np.random.default_rng(seed)):
        d, near = distance_to_path(path, points)
        d0, near0 = kdtree_distance(path, points)
        assert np.array_equal(d, d0)  # every bit of every distance
        assert np.array_equal(near, near0)


def test_a_path_that_retraces_itself_the_same_distances_the_later_pass_s_point() -> None:
    """Passes back and forth over the same points: a point is as near (to the bit) to two
    passes' segments, and the later one's nearest point is given; the k-d tree gave the one
    it met first, which differs from it in the last bit at most."""
    path, points = slot(np.random.default_rng(4), [-0.001] * 6)
    d, near = distance_to_path(path, points)
    d0, near0 = kdtree_distance(path, points)
    assert np.array_equal(d, d0)
    differ = (near != near0).any(axis=1)
    assert 0 < differ.sum() < 100
    np.testing.assert_allclose(near, near0, rtol=0, atol=2e-19)  # 1 ulp of 1 mm: 2.2e-19 m
    assert np.array_equal(np.linalg.norm(points - near, axis=1), d)


# Coordinates on a coarse grid (many exact ties between segments) or anywhere in [-1, 1]
# (the k-d tree search it replaced failed on segments of 1e-203 m: they are left out here).
coordinates = st.one_of(
    st.integers(-8, 8).map(lambda i: i / 8),
    st.floats(-1.0, 1.0).filter(lambda x: x == 0.0 or abs(x) > 1e-6),
)


@settings(max_examples=150, deadline=None)
@given(
    path=arrays(float, st.tuples(st.integers(2, 40), st.just(2)), elements=coordinates),
    points=arrays(float, st.tuples(st.integers(1, 20), st.just(2)), elements=coordinates),
)
def test_the_nearest_segment_by_the_formula_of_any_path(path, points) -> None:
    """Of any path: the smallest of the formula's distances to every segment, to the bit,
    and the nearest point of the last segment that gives it; the k-d tree's distance."""
    d, near = distance_to_path(path, points)
    keep = np.ones(len(path), dtype=bool)
    keep[1:] = np.any(path[1:] != path[:-1], axis=1)
    vertices = path[keep]
    if len(vertices) == 1:
        assert np.array_equal(d, np.linalg.norm(points - vertices[0], axis=1))
        return
    m, n = len(points), len(vertices) - 1
    every, q = _point_segment(
        np.repeat(points, n, axis=0),
        np.tile(vertices[:-1], (m, 1)),
        np.tile(np.diff(vertices, axis=0), (m, 1)),
    )
    every, q = every.reshape(m, n), q.reshape(m, n, 2)
    last = n - 1 - np.argmin(every[:, ::-1], axis=1)
    assert np.array_equal(d, every.min(axis=1))
    assert np.array_equal(near, q[np.arange(m), last])
    assert np.array_equal(d, kdtree_distance(path, points)[0])


def test_non_finite_points_and_vertices() -> None:
    path = np.array([[0.0, 0.0], [np.nan, 5.0], [1.0, 0.0], [1.0, 0.0]])
    d, near = distance_to_path(path, np.array([[0.5, 0.1], [np.nan, 0.0], [2.0, 0.0]]))
    np.testing.assert_allclose(d[[0, 2]], [0.1, 1.0], atol=1e-15)
    assert math.isnan(d[1]) and np.isnan(near[1]).all()
    d, _ = distance_to_path(np.array([[1.0, 2.0]]), np.array([[4.0, 6.0]]))  # a single vertex
    assert d[0] == 5.0
    with pytest.raises(ValueError, match='no finite vertex'):
        distance_to_path(np.full((3, 2), np.nan), np.zeros((1, 2)))


def lagging_run(lag: int, off: float = 0.0) -> RunRecord:
    """A diagonal x-y-z line at 3 mm/s; the tool `lag` samples behind, `off` [m] to its left."""
    rec = RunRecord.empty(2001, 0.001)
    direction = np.array([0.6, 0.8, 0.0])
    s = 0.003 * np.clip(rec.t - 0.2, 0, None)  # along the path [m]
    rec.signals['reference'][:] = s[:, None] * direction
    behind = np.concatenate([np.zeros(lag), s[: s.size - lag]])
    rec.signals['position'][:] = behind[:, None] * direction + off * np.array([-0.8, 0.6, 0.0])
    return rec


def test_a_tool_lagging_along_its_path_has_no_contour_error_but_a_tracking_error() -> None:
    rec = lagging_run(lag=50)
    tracking = {m.axis: m.rms_error for m in summarize(rec, 1.0)}
    assert tracking['x'] == pytest.approx(0.6 * 0.003 * 0.05, rel=1e-9)  # 90 µm behind
    assert tracking['y'] == pytest.approx(0.8 * 0.003 * 0.05, rel=1e-9)
    c = summarize_contour(rec, 1.0)
    assert c is not None and c.axes == 'xyz'
    assert c.max_error <= 1e-15 and c.rms_error <= 1e-15


def test_a_tool_off_its_path_by_d_has_contour_error_d() -> None:
    rec = lagging_run(lag=50, off=4e-6)
    c = summarize_contour(rec, 1.0)
    assert c is not None
    assert c.max_error == pytest.approx(4e-6, rel=1e-9)
    assert c.rms_error == pytest.approx(4e-6, rel=1e-9)
    full = contour_error(rec)
    assert full is not None and full.distance.shape == rec.t.shape
    text = axis_summary(rec, 1.0).text()
    assert text.splitlines()[-1] == (
        'contour error (distance to the programmed x-y-z path): max 0.004000 mm, RMS 0.004000 mm'
    )


def test_the_path_has_the_axes_of_the_run() -> None:
    rec = lagging_run(lag=0, off=1e-5)
    rec.signals['position'][:, 2] = np.nan  # z not in this run; its reference is ignored
    rec.signals['reference'][:, 2] = 1.0
    c = summarize_contour(rec, 1.0)
    assert c is not None and c.axes == 'xy' and c.max_error == pytest.approx(1e-5, rel=1e-9)
    rec.signals['position'][:] = np.nan
    assert contour_error(rec) is None and summarize_contour(rec, 1.0) is None


@pytest.mark.slow
def test_the_main_job_s_contour_error_is_the_k_d_tree_s_to_the_bit() -> None:
    """The main job (slotting, 53,335 samples, offline: the record a run gives): every
    distance and nearest point as the k-d tree search gave them."""
    from mill_bringup.jobs.base import simulate
    from mill_bringup.jobs.registry import job_for
    from mill_bringup.scenario import load

    rec = simulate(job_for(load('slotting')))
    ref, pos = rec['reference'], rec['position']
    assert len(rec.t) == 53335 and np.isfinite(pos).all()
    d, near = distance_to_path(ref, pos)
    d0, near0 = kdtree_distance(ref, pos)
    assert np.array_equal(d, d0) and np.array_equal(near, near0)
