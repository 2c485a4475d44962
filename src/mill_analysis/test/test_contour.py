"""The contour error: the distance to the programmed path (known geometry, and against a
brute-force distance to every segment), not the time-matched tracking error."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mill_analysis.contour import distance_to_path
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


@pytest.mark.parametrize('neighbours', [16, 1])  # 1: most points take the ball search
def test_equals_the_distance_to_every_segment(monkeypatch, neighbours: int) -> None:
    monkeypatch.setattr(contour, 'NEIGHBOURS', neighbours)
    rng = np.random.default_rng(7)
    # a random walk with steps from 1 nm to 1 mm, repeated vertices, and a path that crosses
    # itself: many samples near some points, segments of very different lengths
    steps = rng.normal(size=(2000, 3)) * 10.0 ** rng.uniform(-9, -3, (2000, 1))
    steps[rng.random(2000) < 0.05] = 0.0
    path = np.cumsum(steps, axis=0)
    lo, hi = path.min(axis=0), path.max(axis=0)
    points = np.vstack(
        [
            rng.uniform(lo, hi, (500, 3)),
            path[rng.integers(0, 2000, 500)] + rng.normal(scale=1e-6, size=(500, 3)),
        ]
    )
    d, near = distance_to_path(path, points)
    np.testing.assert_allclose(d, brute_force(path, points), rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(points - near, axis=1), d, rtol=1e-9, atol=1e-15)


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
