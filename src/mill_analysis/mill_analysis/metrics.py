"""The record of one run and the metrics computed from it. ROS-free.

The offline simulator fills a RunRecord directly; the distributed run fills
it from the messages it received. Both go through `summarize`, so the
figures of the two are computed by the same code.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from mill_common.signals import AXES

from mill_analysis.contour import distance_to_path
from mill_analysis.record_checks import Drops

SIGNALS = (
    'position',  # measured position [m]
    'reference',  # reference position [m]
    'reference_velocity',  # [m/s]
    'estimate_velocity',  # observer velocity [m/s]
    'estimate_disturbance',  # observer xi [m/s^2]
    'torque',  # commanded torque [N m]
    'true_velocity',  # plant velocity [m/s] (simulation only)
    'true_disturbance',  # plant xi [m/s^2] (simulation only)
    'force',  # cutting force [N]
)


# /mill/force_control/state of each control instant, with its time first
FORCE_CONTROL = ('t', 'force', 'reference', 'feed_command', 'override', 'beta', 'depth')


@dataclass
class RunRecord:
    """Signals of a run on the sample grid t[k] = k T; absent values are NaN."""

    t: np.ndarray
    signals: dict[str, np.ndarray] = field(default_factory=dict)
    events: list[str] = field(default_factory=list)  # what happened besides the signals
    # Messages left out per topic: what the nodes drop (mill_analysis.record_checks): sent by
    # another node than the topic's owner, a stamp they refuse, or malformed; and why.
    foreign: dict[str, int] = field(default_factory=dict)
    drops: Drops = field(default_factory=Drops)
    # Per topic, the runs (first, last) of the samples it lacks.
    gaps: dict[str, list[tuple[int, int]]] = field(default_factory=dict)
    # A job with a force controller: one row per control instant, columns FORCE_CONTROL
    force_control: np.ndarray | None = None

    @classmethod
    def empty(cls, n: int, dt: float) -> RunRecord:
        t = np.arange(n) * dt
        return cls(t, {s: np.full((n, len(AXES)), np.nan) for s in SIGNALS})

    def trimmed(self, n: int) -> RunRecord:
        """The first n samples (a job that ended before the space it was given)."""
        return RunRecord(
            self.t[:n],
            {k: v[:n] for k, v in self.signals.items()},
            self.events,
            self.foreign,
            self.drops,
            self.gaps,
            self.force_control,
        )

    def grown(self, n: int, dt: float) -> RunRecord:
        """Room for n samples t = k dt: the present ones, then NaN."""
        old = len(self.t)
        out = RunRecord.empty(n, dt)
        for k, v in self.signals.items():
            out.signals[k][:old] = v
        out.events, out.foreign, out.force_control = self.events, self.foreign, self.force_control
        out.drops, out.gaps = self.drops, self.gaps
        return out

    def __getitem__(self, name: str) -> np.ndarray:
        return self.signals[name]

    @property
    def tracking_error(self) -> np.ndarray:
        return self['position'] - self['reference']

    @property
    def disturbance_error(self) -> np.ndarray:
        return self['estimate_disturbance'] - self['true_disturbance']


@dataclass(frozen=True)
class AxisMetrics:
    axis: str
    max_error: float  # max |e| after the skip [m]
    rms_error: float  # RMS e after the skip [m]
    rms_disturbance_error: float  # RMS (xi_hat - xi) after the skip [m/s^2]
    rms_disturbance: float  # RMS xi after the skip, for scale [m/s^2]


def _rms(x: np.ndarray) -> float:
    x = x[np.isfinite(x)]
    return float(np.sqrt(np.mean(x * x))) if x.size else math.nan


def _max_abs(x: np.ndarray) -> float:
    x = x[np.isfinite(x)]
    return float(np.max(np.abs(x))) if x.size else math.nan


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
        out.append(
            AxisMetrics(axis, _max_abs(e[:, i]), _rms(e[:, i]), _rms(d[:, i]), _rms(xi[:, i]))
        )
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


def contour_error(record: RunRecord) -> Contour | None:
    """The contour error: for each sample, the distance from the measured position to the
    programmed path, the polyline through every reference position of the run, in the space
    of the run's axes (those with a measured position; 3-D for x, y, z). It is the distance
    to the nearest point of the path, not to the reference of the same instant: a tool that
    lags along its path has a tracking error but no contour error; a corner cut short has
    one. What a machinist measures on the part. None for a run without a measured axis.
    """
    cols = [i for i in range(len(AXES)) if np.isfinite(record['position'][:, i]).any()]
    ref = record['reference'][:, cols]
    if not cols or not np.isfinite(ref).all(axis=1).any():
        return None
    distance, near = distance_to_path(ref, record['position'][:, cols])
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
    return ContourMetrics(contour.axes, _max_abs(after), _rms(after))


def summary_text(record: RunRecord, skip: float) -> str:
    """The summary a run prints: per-axis metrics and the contour error."""
    return format_summary(summarize(record, skip), skip, summarize_contour(record, skip))


def format_summary(
    metrics: list[AxisMetrics], skip: float, contour: ContourMetrics | None = None
) -> str:
    lines = [
        f'axis   max |e| [mm]   RMS e [mm]   RMS(xi_hat - xi) [m/s^2]   RMS xi [m/s^2]'
        f'   (t >= {skip:g} s)'
    ]
    for m in metrics:
        lines.append(
            f'{m.axis:>4}   {m.max_error * 1e3:12.6f}   {m.rms_error * 1e3:10.6f}'
            f'   {m.rms_disturbance_error:24.6f}   {m.rms_disturbance:14.6f}'
        )
    if contour is not None:
        lines.append(
            f'contour error (distance to the programmed {"-".join(contour.axes)} path): '
            f'max {contour.max_error * 1e3:.6f} mm, RMS {contour.rms_error * 1e3:.6f} mm'
        )
    return '\n'.join(lines)
