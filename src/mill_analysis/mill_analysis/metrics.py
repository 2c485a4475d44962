"""Every figure computed from a run, each defined once with its window and NaN rule. ROS-free.

In the manner of python-control's `step_info`: plain functions of arrays, used by the run
summaries (mill_analysis.summary: the text, the JSON and `report` print from it), the
papers' verdicts and `tune`'s prediction.

- NaN rule: a sample that is not finite (not measured, lost) is left out of every figure;
  a figure over no finite sample is NaN, never 0.
- Window: the samples with start <= t < end (`Window`); a summary's window starts at its
  `skip` (the start transient left out) and ends at the record's end.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from mill_common.signals import AXES

from mill_analysis.contour import distance_to_path
from mill_analysis.record import RunRecord


@dataclass(frozen=True)
class Window:
    """The samples a figure is computed over: start <= t < end [s]."""

    start: float
    end: float = math.inf

    def mask(self, t: np.ndarray) -> np.ndarray:
        return (t >= self.start) & (t < self.end)


def finite(x: np.ndarray) -> np.ndarray:
    """The finite samples of x (the NaN rule)."""
    x = np.asarray(x)
    return x[np.isfinite(x)]


def rms(x: np.ndarray) -> float:
    """Root mean square of the finite samples of x; NaN if there is none."""
    x = finite(x)
    return float(np.sqrt(np.mean(x * x))) if x.size else math.nan


def peak(x: np.ndarray) -> float:
    """Largest |x| over the finite samples; NaN if there is none."""
    x = finite(x)
    return float(np.max(np.abs(x))) if x.size else math.nan


@dataclass(frozen=True)
class AxisMetrics:
    axis: str
    max_error: float  # max |e| after the skip [m]
    rms_error: float  # RMS e after the skip [m]
    rms_disturbance_error: float  # RMS (xi_hat - xi) after the skip [m/s^2]
    rms_disturbance: float  # RMS xi after the skip, for scale [m/s^2]


def summarize(record: RunRecord, skip: float = 1.0) -> list[AxisMetrics]:
    """Per-axis metrics over t >= skip (the start transient is excluded)."""
    after = record.t >= skip
    e = record.tracking_error[after]
    d = record.disturbance_error[after]
    xi = record['true_disturbance'][after]
    out = []
    for i, axis in enumerate(AXES):
        if not np.isfinite(record['position'][:, i]).any():
            continue  # axis not in this run
        out.append(AxisMetrics(axis, peak(e[:, i]), rms(e[:, i]), rms(d[:, i]), rms(xi[:, i])))
    return out


@dataclass(frozen=True)
class Contour:
    """The contour error of a run, per sample (see `contour_error`)."""

    axes: str  # the axes of the path, e.g. 'xyz'
    distance: np.ndarray  # (n,) [m], NaN where the measured position is not known
    nearest: np.ndarray  # (n, 3): the nearest point of the path [m], NaN off its axes


@dataclass(frozen=True)
class ContourMetrics:
    axes: str  # the axes of the path
    max_error: float  # max contour error after the skip [m]
    rms_error: float  # RMS contour error after the skip [m]


def contour_error(record: RunRecord, path_from: float = -math.inf) -> Contour | None:
    """The contour error: for each sample, the distance from the measured position to the
    programmed path, the polyline through every reference position of the run, in the space
    of the run's axes (those with a measured position; 3-D for x, y, z). It is the distance
    to the nearest point of the path, not to the reference of the same instant: a tool that
    lags along its path has a tracking error but no contour error; a corner cut short has
    one. What a machinist measures on the part. None for a run without a measured axis.
    path_from: the path's references from this time on [s] (a realtime job's approach to the
    path's start, before it, is no part of the programmed path).
    """
    cols = [i for i in range(len(AXES)) if np.isfinite(record['position'][:, i]).any()]
    every = len(cols) == len(AXES)  # the record's own arrays, not copies (1.3 MB each)
    ref = record['reference'] if every else record['reference'][:, cols]
    path = record.t >= path_from
    if not path.all():
        ref = ref[path]
    if not cols or not np.isfinite(ref).all(axis=1).any():
        return None
    distance, near = distance_to_path(
        ref, record['position'] if every else record['position'][:, cols]
    )
    if every:
        return Contour(''.join(AXES), distance, near)
    nearest = np.full((len(record.t), len(AXES)), np.nan)
    nearest[:, cols] = near
    return Contour(''.join(AXES[i] for i in cols), distance, nearest)


def summarize_contour(
    record: RunRecord, skip: float = 1.0, contour: Contour | None = None
) -> ContourMetrics | None:
    """Max and RMS contour error over t >= skip (`contour_error`, computed if not given)."""
    if contour is None:
        contour = contour_error(record)
    if contour is None:
        return None
    after = contour.distance[record.t >= skip]
    return ContourMetrics(contour.axes, peak(after), rms(after))


def max_difference(a: np.ndarray, b: np.ndarray) -> float:
    """Largest |a − b| over all entries; 0 where both are NaN, inf where only one is (or the
    shapes differ)."""
    if a.shape != b.shape:
        return math.inf
    diff = np.abs(a - b)
    diff[np.isnan(a) & np.isnan(b)] = 0.0
    diff[np.isnan(diff)] = np.inf
    return float(diff.max()) if diff.size else 0.0
