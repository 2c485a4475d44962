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


def format_summary(metrics: list[AxisMetrics], skip: float) -> str:
    lines = [
        f'axis   max |e| [mm]   RMS e [mm]   RMS(xi_hat - xi) [m/s^2]   RMS xi [m/s^2]'
        f'   (t >= {skip:g} s)'
    ]
    for m in metrics:
        lines.append(
            f'{m.axis:>4}   {m.max_error * 1e3:12.6f}   {m.rms_error * 1e3:10.6f}'
            f'   {m.rms_disturbance_error:24.6f}   {m.rms_disturbance:14.6f}'
        )
    return '\n'.join(lines)
