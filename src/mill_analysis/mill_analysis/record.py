"""The record of one run: its signals on the sample grid, and what was left out. ROS-free.

The offline simulator fills a RunRecord directly; the distributed run fills it from the
messages it received (mill_analysis.lockstep_record, realtime_record); mill_analysis.metrics
computes every figure from it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from mill_common.signals import AXES

from mill_analysis.events import Event
from mill_analysis.node_intake import Drops

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
    # What happened besides the signals (mill_analysis.events): a trip, a stop, a brake.
    events: list[Event] = field(default_factory=list)
    # Messages left out per topic: what the nodes drop (mill_analysis.node_intake): sent by
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
