"""The distance from points to a polyline path, and its nearest points. ROS-free, numpy only.

The contour error of a run (mill_analysis.metrics) is the distance from each measured
position to the programmed path, the polyline through the reference positions; this is its
geometry. Exact: the distance to each segment that may be the nearest is measured with the
point-to-segment formula (`_point_segment`), and the smallest is the answer.

Which segments may be the nearest: a tree of boxes over consecutive segments (a box holds
FANOUT segments, a box above FANOUT boxes, up to at most FANOUT at the top). Walking down
from the top, a point keeps the boxes not farther than the nearest vertex of the path it has
seen (the first vertex of each box it looked at), with a margin far above the rounding of
the formula; at the bottom it measures the segments it kept. A path's segments follow each
other, so a box of consecutive ones is small: a point near the path keeps a few boxes a
level, and the search costs O(M log N) for M points and N vertices. Points are taken BLOCK
at a time (each point's answer is its own); a block whose candidates would exceed MAX_PAIRS
is split. No k-d tree: scipy.spatial's cost a runner 37 MB for its summary, and this gives
the same distances to the bit (the same formula, the same minimum; test_contour).
"""

from __future__ import annotations

import numpy as np

FANOUT = 4  # segments (boxes) a box holds: 4 measured fastest on the main job's path
BLOCK = 512  # points searched at once
MAX_PAIRS = 1 << 20  # (point, box) candidates of a block above which it is split
# The margin of a box kept beside a point's best one: relative to the distance, and to the
# coordinates' size (the formula's rounding is a few units of 1e-16 of them).
RELATIVE_MARGIN = 1e-9
SCALE_MARGIN = 1e-12


def distance_to_path(path: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(distance, nearest): for each of the M points (M, D), its Euclidean distance to the
    polyline through the path's vertices (N, D) and the nearest point on it.

    Vertices with a non-finite coordinate are left out (the path goes straight across a gap);
    a point with one gets NaN. A path of a single vertex is that point. Of segments equally
    near (to the bit), the later one's nearest point is given (at a vertex: the vertex).
    """
    path = np.asarray(path, dtype=float)
    points = np.asarray(points, dtype=float)
    finite = np.isfinite(path).all(axis=1)
    if not finite.all():  # (a copy only then: the main job's path is 1.3 MB)
        path = path[finite]
    if len(path) == 0:
        raise ValueError('the path has no finite vertex')
    keep = np.ones(len(path), dtype=bool)
    keep[1:] = np.any(path[1:] != path[:-1], axis=1)  # a zero-length segment is no segment
    if not keep.all():
        path = path[keep]
    if len(path) == 1:
        near = np.where(np.isfinite(points).all(axis=1)[:, None], path[0], np.nan)
        return np.linalg.norm(points - near, axis=1), near
    boxes = _Boxes(path)
    distance = np.full(len(points), np.nan)
    nearest = np.full(points.shape, np.nan)
    ok = np.flatnonzero(np.isfinite(points).all(axis=1))
    for lo in range(0, ok.size, BLOCK):
        boxes.search(points, ok[lo : lo + BLOCK], distance, nearest)
    return distance, nearest


class _Boxes:
    """The path's segments and the tree of boxes over them: level 0 the segments (sizes[0]
    of them), level L >= 1 boxes of FANOUT boxes (segments) of level L - 1 (sizes[L])."""

    def __init__(self, path: np.ndarray) -> None:
        self.start, self.vec = path[:-1], np.diff(path, axis=0)
        self.sizes = [len(self.start)]
        # Each level above the segments: the boxes' corners, and a vertex of the path in
        # each (its first); level 1 from the vertices (segment g FANOUT + j, 0 <= j < FANOUT,
        # ends at vertex g FANOUT + j + 1).
        first = np.arange(0, len(self.start), FANOUT)
        last = path[np.minimum(first + FANOUT, len(path) - 1)]
        lo = np.minimum(np.minimum.reduceat(self.start, first), last)
        hi = np.maximum(np.maximum.reduceat(self.start, first), last)
        self.levels = [(lo, hi, self.start[::FANOUT])]
        step = FANOUT
        while len(lo) > FANOUT:
            first = np.arange(0, len(lo), FANOUT)
            lo, hi = np.minimum.reduceat(lo, first), np.maximum.reduceat(hi, first)
            step *= FANOUT
            self.levels.append((lo, hi, self.start[::step]))
        self.sizes += [len(lo) for lo, _, _ in self.levels]
        self.scale = float(np.max(np.abs(path)))

    def search(
        self, points: np.ndarray, rows_of: np.ndarray, distance: np.ndarray, nearest: np.ndarray
    ) -> None:
        """distance and nearest of the points at rows_of (finite), in place."""
        pts = points[rows_of]
        scale = max(self.scale, float(np.max(np.abs(pts))))
        top = self.sizes[-1]
        rows = np.repeat(np.arange(len(pts)), top)  # sorted: each level keeps the order
        nodes = np.tile(np.arange(top), len(pts))
        reach = np.full(len(pts), np.inf)  # per point, the square of a distance to the path
        for level in range(len(self.sizes) - 1, 0, -1):
            rows, nodes = self._kept(pts, rows, nodes, self.levels[level - 1], reach, scale)
            rows, nodes = _children(rows, nodes, self.sizes[level - 1])
            if rows.size > MAX_PAIRS and len(pts) > 1:
                half = len(rows_of) // 2
                self.search(points, rows_of[:half], distance, nearest)
                self.search(points, rows_of[half:], distance, nearest)
                return
        d, q = _point_segment(pts[rows], self.start[nodes], self.vec[nodes])
        order = np.lexsort((-nodes, d, rows))  # per point the nearest, the later first
        first = order[np.flatnonzero(np.diff(rows[order], prepend=-1))]
        distance[rows_of[rows[first]]] = d[first]
        nearest[rows_of[rows[first]]] = q[first]

    @staticmethod
    def _kept(
        pts: np.ndarray,
        rows: np.ndarray,
        nodes: np.ndarray,
        level: tuple[np.ndarray, np.ndarray, np.ndarray],
        reach: np.ndarray,
        scale: float,
    ) -> tuple[np.ndarray, np.ndarray]:
        """The (point, box) pairs whose box may hold the point's nearest segment; `reach`
        (per point, the square of its distance to a vertex) lowered to the vertices seen."""
        p = pts[rows]
        gap = np.maximum(np.maximum(level[0][nodes] - p, p - level[1][nodes]), 0.0)
        below = np.einsum('ij,ij->i', gap, gap)  # to the box, squared
        to_vertex = p - level[2][nodes]
        vertex = np.einsum('ij,ij->i', to_vertex, to_vertex)
        starts = np.flatnonzero(np.diff(rows, prepend=-1))
        np.minimum(reach, np.minimum.reduceat(vertex, starts), out=reach)
        near = reach[rows]
        margin = np.sqrt(near) * RELATIVE_MARGIN + SCALE_MARGIN * scale
        keep = below <= near + margin * (2 * np.sqrt(near) + margin)  # (d + margin)²
        return rows[keep], nodes[keep]


def _children(rows: np.ndarray, nodes: np.ndarray, below: int) -> tuple[np.ndarray, np.ndarray]:
    """Each (point, box) pair as the pairs of its boxes (segments) one level down."""
    first = nodes * FANOUT
    count = np.minimum(FANOUT, below - first)
    offset = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
    return np.repeat(rows, count), np.repeat(first, count) + offset


def _point_segment(p: np.ndarray, a: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Row by row: the distance from p to the segment a + s v, s in [0, 1], and its point."""
    vv = np.einsum('ij,ij->i', v, v)
    s = np.einsum('ij,ij->i', p - a, v) / np.where(vv > 0, vv, 1.0)
    q = a + np.clip(s, 0.0, 1.0)[:, None] * v
    return np.linalg.norm(p - q, axis=1), q
