"""The distance from points to a polyline path, and its nearest points. ROS-free.

The contour error of a run (mill_analysis.metrics) is the distance from each measured
position to the programmed path, the polyline through the reference positions; this is its
geometry. Exact (point-to-segment distance), in O((N + M) log N) for N path vertices and
M points: a k-d tree over points spaced at most h along the path gives each point's nearest
sample at d0; the nearest point of the path is within h/2 of a sample, so every segment that
may hold it has a sample within d0 + h/2, and only those segments are measured exactly.
"""

from __future__ import annotations

from typing import Any

import numpy as np

# Samples h apart, h the median segment length (a path sampled at T: its vertices), but at
# most MAX_SAMPLES of them, whatever the path's length
MAX_SAMPLES = 400_000
NEIGHBOURS = 16  # samples measured per point before a wider (ball) search is needed
BLOCK = 1024  # points measured at once


def distance_to_path(path: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(distance, nearest): for each of the M points (M, D), its Euclidean distance to the
    polyline through the path's vertices (N, D) and the nearest point on it.

    Vertices with a non-finite coordinate are left out (the path goes straight across a gap);
    a point with one gets NaN. A path of a single vertex is that point.
    """
    path = np.asarray(path, dtype=float)
    points = np.asarray(points, dtype=float)
    path = path[np.isfinite(path).all(axis=1)]
    if len(path) == 0:
        raise ValueError('the path has no finite vertex')
    keep = np.ones(len(path), dtype=bool)
    keep[1:] = np.any(path[1:] != path[:-1], axis=1)  # a zero-length segment is no segment
    path = path[keep]
    if len(path) == 1:
        near = np.where(np.isfinite(points).all(axis=1)[:, None], path[0], np.nan)
        return np.linalg.norm(points - near, axis=1), near
    start, vec = path[:-1], np.diff(path, axis=0)
    length = np.linalg.norm(vec, axis=1)
    h = max(float(length.sum()) / MAX_SAMPLES, float(np.median(length)))
    pieces = np.maximum(1, np.ceil(length / h)).astype(int)  # samples per segment
    spacing = float(np.max(length / pieces))
    seg = np.repeat(np.arange(len(start)), pieces)  # each sample's segment
    frac = (np.arange(seg.size) - np.repeat(np.cumsum(pieces) - pieces, pieces)) / pieces[seg]
    samples = np.vstack([start[seg] + frac[:, None] * vec[seg], path[-1:]])
    seg = np.append(seg, len(start) - 1)
    from scipy.spatial import cKDTree  # here: 37 MB a runner needs only for its summary

    tree = cKDTree(samples)

    distance = np.full(len(points), np.nan)
    nearest = np.full(points.shape, np.nan)
    ok = np.flatnonzero(np.isfinite(points).all(axis=1))
    if ok.size == 0:
        return distance, nearest
    k = min(NEIGHBOURS, len(samples))
    # In blocks of points: each point's answer is its own, and the candidates of all of
    # them at once take ~1 kB a point (77 MB for the main job's summary).
    for lo in range(0, ok.size, BLOCK):
        rows_of = ok[lo : lo + BLOCK]
        d, q = _nearest(tree, samples, seg, start, vec, spacing, k, points[rows_of])
        distance[rows_of] = d
        nearest[rows_of] = q
    return distance, nearest


def _nearest(
    tree: Any,
    samples: np.ndarray,
    seg: np.ndarray,
    start: np.ndarray,
    vec: np.ndarray,
    spacing: float,
    k: int,
    pts: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """distance_to_path's answer for finite points pts: distance and nearest point."""
    dist, idx = tree.query(pts, k=k)
    dist, idx = dist.reshape(len(pts), k), idx.reshape(len(pts), k)
    reach = dist[:, 0] + 0.5 * spacing * (1 + 1e-9) + 1e-15
    covered = (dist[:, -1] > reach) | (k == len(samples))
    within = (dist <= reach[:, None]) & covered[:, None]  # the samples that matter
    rows = np.nonzero(within)[0]
    cand = idx[within]
    wide = np.flatnonzero(~covered)  # the k nearest may miss a segment: all within reach
    if wide.size:
        balls = tree.query_ball_point(pts[wide], reach[wide])
        sizes = np.array([len(b) for b in balls])
        rows = np.concatenate([rows, np.repeat(wide, sizes)])
        cand = np.concatenate([cand, np.concatenate([np.asarray(b, dtype=int) for b in balls])])
    # a sample at a segment's start is also the end of the one before
    segs = np.concatenate([seg[cand], np.maximum(seg[cand] - 1, 0)])
    rows = np.concatenate([rows, rows])
    d, q = _point_segment(pts[rows], start[segs], vec[segs])
    order = np.lexsort((d, rows))  # per row, the nearest first
    first = order[np.flatnonzero(np.diff(rows[order], prepend=-1))]
    out_d = np.full(len(pts), np.nan)
    out_q = np.full(pts.shape, np.nan)
    out_d[rows[first]] = d[first]
    out_q[rows[first]] = q[first]
    return out_d, out_q


def _point_segment(p: np.ndarray, a: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Row by row: the distance from p to the segment a + s v, s in [0, 1], and its point."""
    vv = np.einsum('ij,ij->i', v, v)
    s = np.einsum('ij,ij->i', p - a, v) / np.where(vv > 0, vv, 1.0)
    q = a + np.clip(s, 0.0, 1.0)[:, None] * v
    return np.linalg.norm(p - q, axis=1), q
