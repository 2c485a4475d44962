"""A run's summary as one value: every figure, over one window, and what happened. ROS-free.

One frozen dataclass per kind of job (`AxisSummary`, `ForceSummary`), built once from a
record (`axis_summary`, `force_summary`); the runner's text and its summary.json, `report`
and the comparison with `tune`'s prediction all print from it: `to_json` is the value as
JSON, `from_json` reads it back, and `text` prints it, so the text and the JSON agree.

The window (mill_analysis.metrics.Window) is the same for every figure of a summary: from
`skip` seconds after the job's path started (a realtime job first moves from where the axes
stand to the path's start: that approach is left out, and the contour error's path starts
after it too) to the record's end. An axis that was tripped, stopped or braked
(mill_analysis.events) has its figures up to that moment, and says so; the contour error,
of every axis at once, ends at the first such moment.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np
from mill_common.signals import AXES

from mill_analysis import drive_status as keys
from mill_analysis.events import BRAKED, STOPPED, TRIP, Event
from mill_analysis.metrics import ContourMetrics, Window, contour_error, peak, rms
from mill_analysis.record import RunRecord

# What a stopped axis says after its figures, by the kind of its first stop.
STOP_WORDS = {TRIP: 'tripped', STOPPED: 'stopped', BRAKED: 'braked'}
WORSE = 2.0  # a run this many times the predicted RMS error is reported as a warning


@dataclass(frozen=True)
class AxisFigures:
    """One axis's figures over the summary's window, up to `stopped_at` if it stopped."""

    axis: str
    max_error: float  # max |e| [m]
    rms_error: float  # RMS e [m]
    rms_disturbance_error: float  # RMS (xi_hat - xi) [m/s^2]
    rms_disturbance: float  # RMS xi, for scale [m/s^2]
    stopped_at: float | None = None  # tripped, stopped or braked then [s]: the figures end
    stop: str = ''  # how: 'tripped', 'stopped', 'braked'


@dataclass(frozen=True)
class PredictionComparison:
    """The run's RMS e beside `tune`'s prediction (tuning/prediction_file.py), both over the
    job's window after the approach; `note` says why it was not compared ('' if it was)."""

    source: str  # the parameter file, and the -p the prediction was made with
    measured: Mapping[str, float] = field(default_factory=dict)  # RMS e per axis [m]
    predicted: Mapping[str, float] = field(default_factory=dict)  # [m]
    note: str = ''

    @property
    def worse(self) -> list[str]:
        """The axes that tracked more than WORSE times worse than predicted."""
        return [a for a, m in self.measured.items() if not m / self.predicted[a] <= WORSE]

    def lines(self) -> list[str]:
        if self.note:
            return [self.note]
        cells = []
        for axis, m in self.measured.items():
            p = self.predicted[axis]
            cells.append(f'{axis} {1e6 * m:.3g} / {1e6 * p:.3g} ({m / p:.2f}x)')
        out = [f'RMS e [µm] measured / predicted by tune ({self.source}): ' + ', '.join(cells)]
        if self.worse:
            out.append(
                f'WARNING: {", ".join(self.worse)} tracked more than {WORSE:g}x worse than '
                'predicted: the machine is not the one identified (re-identify: '
                'docs/bring-up.md)'
            )
        return out


DRIVE_FIGURES = keys.FIGURES  # per axis, as the drive's status names them


@dataclass(frozen=True)
class DriveFigures:
    """A realtime run's drive: per axis its periods without a fresh command and the
    state -> command latency (DRIVE_FIGURES), where they come from, and its late ticks."""

    source: str  # 'the drive', or 'the commands as the runner received them'
    axes: Mapping[str, Mapping[str, float]]
    overruns: int  # ticks more than half a period late
    ticks: int  # ticks while active (0: the driver does not say)
    # its own stalls (ticks that woke more than stall_report_ms late, monotonic clock): how
    # many, the longest [ms] and its line (which process, when)
    stalls: int = 0
    longest_stall_ms: float = 0.0
    longest_stall: str = ''
    stall_report_ms: str = '?'  # as the drive says it

    def lines(self) -> list[str]:
        out = [
            'axis   periods without a fresh command   in a row   state->command latency [ms]: '
            f'median    p99     max   (from {self.source})'
        ]
        for axis, f in self.axes.items():
            out.append(
                f'{axis:>4}   {100 * f["late_fraction"]:30.2f} %   '
                f'{f["longest_late_run"]:8.0f}   {f["latency_median_ms"]:27.3f} '
                f'{f["latency_p99_ms"]:7.3f} {f["latency_max_ms"]:7.3f}'
            )
        if self.overruns:
            of = (
                f' of {self.ticks} ({100 * self.overruns / self.ticks:.2f} %)' if self.ticks else ''
            )
            out.append(
                f'WARNING: the drive ticked more than half a period late {self.overruns} times'
                f'{of}: this machine does not hold the sample rate in this layout'
            )
        if self.stalls:
            out.append(
                f'WARNING: the drive stalled {self.stalls} times by more than '
                f'{self.stall_report_ms} ms (monotonic), the longest: {self.longest_stall}; '
                'its own stalls, not late commands'
            )
        return out


@dataclass(frozen=True)
class DepthStretch:
    """Control instants at one depth of cut, averaged over the second half of the stretch."""

    depth: float  # [mm]
    start: float  # first instant at this depth [s]
    end: float  # last instant [s]
    instants: int
    force: float  # mean force the law used [N]
    reference: float  # mean reference [N]
    override: float  # mean override [-]


@dataclass(frozen=True)
class AxisSummary:
    """The three-axis job's summary (lockstep or realtime)."""

    skip: float  # [s] after the path's start
    approach: float  # [s] the realtime job's move to the path's start (0: none)
    window: Window  # every figure's: [approach + skip, the record's end)
    axes: tuple[AxisFigures, ...]
    contour: ContourMetrics | None
    contour_until: float | None = None  # the first stop: the contour error ends there [s]
    events: tuple[Event, ...] = ()
    failures: tuple[Event, ...] = ()  # the events that fail the job (a realtime run's)
    predictions: tuple[PredictionComparison, ...] = ()
    force_control: tuple[DepthStretch, ...] | None = None
    job_end_time: float | None = None  # a job with a force controller: where its path ended
    drive: DriveFigures | None = None  # a realtime run's
    start_stamp_ns: int | None = None  # a realtime run's start on the system clock
    planned_feed: str = ''  # a G-code program's: how much of its feed the plan holds
    # a lockstep run's: how many steps the plant waited over each threshold [ms] (the graph
    # stalled), and the longest wait (mill_common.step_waits)
    step_waits: Mapping[int, int] | None = None
    longest_wait_ms: float = math.nan

    # -- text --------------------------------------------------------------------------------
    def figure_lines(self) -> list[str]:
        """The per-axis figures and the contour error (what `report` prints of a bag too)."""
        after = f't >= {self.skip:g} s'
        if self.approach > 0:
            after = f't >= {self.window.start:g} s: {self.skip:g} s after the approach of ' + (
                f'{self.approach:.3f} s'
            )
        lines = [
            f'axis   max |e| [mm]   RMS e [mm]   RMS(xi_hat - xi) [m/s^2]   RMS xi [m/s^2]'
            f'   ({after})'
        ]
        for m in self.axes:
            line = (
                f'{m.axis:>4}   {m.max_error * 1e3:12.6f}   {m.rms_error * 1e3:10.6f}'
                f'   {m.rms_disturbance_error:24.6f}   {m.rms_disturbance:14.6f}'
            )
            if m.stopped_at is not None:
                line += f'   {m.stop} at t = {m.stopped_at:.4f} s: figures up to then'
            lines.append(line)
        c = self.contour
        if c is not None:
            until = '' if self.contour_until is None else f', up to t = {self.contour_until:.4f} s'
            lines.append(
                f'contour error (distance to the programmed {"-".join(c.axes)} path): '
                f'max {c.max_error * 1e3:.6f} mm, RMS {c.rms_error * 1e3:.6f} mm{until}'
            )
        return lines

    def lines(self) -> list[str]:
        out = self.figure_lines()
        if self.planned_feed:
            out.append(self.planned_feed)
        for p in self.predictions:
            out += p.lines()
        out += [e.text() for e in self.events]
        if self.drive is not None:
            out += self.drive.lines()
        if self.step_waits is not None:
            over = ' / '.join(str(n) for n in self.step_waits.values())
            limits = ' / '.join(str(t) for t in self.step_waits)
            out.append(
                f'lockstep steps that waited over {limits} ms: {over} '
                f'(the longest {self.longest_wait_ms:.1f} ms)'
            )
        if self.force_control:
            out += [
                'force control, per constant depth of cut told (second half of each stretch, '
                'where the force has settled):',
                f'{"depth [mm]":>10} {"from [s]":>9} {"to [s]":>8} {"instants":>9} '
                f'{"force [N]":>10} {"reference [N]":>14} {"override":>9}',
            ]
            out += [
                f'{s.depth:10.3f} {s.start:9.3f} {s.end:8.3f} {s.instants:9d} '
                f'{s.force:10.1f} {s.reference:14.1f} {s.override:9.4f}'
                for s in self.force_control
            ]
        return out

    def text(self) -> str:
        return '\n'.join(self.lines())

    # -- JSON --------------------------------------------------------------------------------
    def to_json(self) -> dict[str, Any]:
        c = self.contour
        out: dict[str, Any] = {
            'window': {'skip': self.skip, 'approach': self.approach, 'start': self.window.start},
            'metrics': [vars(m) for m in self.axes],
            'contour_error': vars(c) if c is not None else None,
            'contour_until': self.contour_until,
            'events': [e.to_json() for e in self.events],
            'failures': [e.to_json() for e in self.failures],
            'predictions': [
                {
                    'source': p.source,
                    'measured': dict(p.measured),
                    'predicted': dict(p.predicted),
                    'note': p.note,
                }
                for p in self.predictions
            ],
        }
        if self.force_control is not None:
            out['force_control'] = [vars(s) for s in self.force_control]
            out['job_end_time'] = self.job_end_time
        if self.drive is not None:
            out['drive'] = {a: dict(f) for a, f in self.drive.axes.items()}
            out['drive_source'] = self.drive.source
            out['drive_overruns'], out['drive_ticks'] = self.drive.overruns, self.drive.ticks
            out['drive_stalls'] = {
                'count': self.drive.stalls,
                'longest_ms': self.drive.longest_stall_ms,
                'longest': self.drive.longest_stall,
                'report_ms': self.drive.stall_report_ms,
            }
            out['start_stamp_ns'] = self.start_stamp_ns
        if self.planned_feed:
            out['planned_feed'] = self.planned_feed
        if self.step_waits is not None:
            out['step_waits'] = {
                'over_ms': {str(t): n for t, n in self.step_waits.items()},
                'longest_ms': self.longest_wait_ms,
            }
        return out

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> AxisSummary:
        w = d['window']
        c = d['contour_error']
        drive = None
        if 'drive' in d:
            stalls = d.get('drive_stalls') or {}
            drive = DriveFigures(
                d['drive_source'],
                d['drive'],
                int(d['drive_overruns']),
                int(d['drive_ticks']),
                stalls=int(stalls.get('count', 0)),
                longest_stall_ms=float(stalls.get('longest_ms', 0.0)),
                longest_stall=str(stalls.get('longest', '')),
                stall_report_ms=str(stalls.get('report_ms', '?')),
            )
        force = d.get('force_control')
        waits = d.get('step_waits')
        return cls(
            skip=float(w['skip']),
            approach=float(w['approach']),
            window=Window(float(w['start'])),
            axes=tuple(AxisFigures(**m) for m in d['metrics']),
            contour=ContourMetrics(**c) if c is not None else None,
            contour_until=d.get('contour_until'),
            events=tuple(Event.from_json(e) for e in d['events']),
            failures=tuple(Event.from_json(e) for e in d['failures']),
            predictions=tuple(PredictionComparison(**p) for p in d['predictions']),
            force_control=None if force is None else tuple(DepthStretch(**s) for s in force),
            job_end_time=d.get('job_end_time'),
            drive=drive,
            start_stamp_ns=d.get('start_stamp_ns'),
            planned_feed=d.get('planned_feed', ''),
            step_waits=None
            if waits is None
            else {int(t): int(n) for t, n in waits['over_ms'].items()},
            longest_wait_ms=math.nan if waits is None else float(waits['longest_ms']),
        )


def first_stops(events: Sequence[Event]) -> dict[str, tuple[float, str]]:
    """Per axis, its first trip, stop or brake: (time, the word for it)."""
    out: dict[str, tuple[float, str]] = {}
    for e in events:
        known = e.kind in STOP_WORDS and math.isfinite(e.time)
        if known and (e.axis not in out or e.time < out[e.axis][0]):
            out[e.axis] = (e.time, STOP_WORDS[e.kind])
    return out


def axis_figures(
    record: RunRecord, window: Window, stops: Mapping[str, tuple[float, str]] | None = None
) -> list[AxisFigures]:
    """Per axis with a measured position, its figures over the window, each cut at the
    axis's stop (stops: per axis, (time, word))."""
    stops = stops or {}
    e, d, xi = record.tracking_error, record.disturbance_error, record['true_disturbance']
    out = []
    for i, axis in enumerate(AXES):
        if not np.isfinite(record['position'][:, i]).any():
            continue  # axis not in this run
        at, word = stops.get(axis, (None, ''))
        end = window.end if at is None else min(window.end, at)
        keep = Window(window.start, end).mask(record.t)
        figures = (peak(e[keep, i]), rms(e[keep, i]), rms(d[keep, i]), rms(xi[keep, i]))
        out.append(AxisFigures(axis, *figures, stopped_at=at, stop=word))
    return out


def contour_figures(
    record: RunRecord, window: Window, path_from: float = -math.inf
) -> ContourMetrics | None:
    """Max and RMS contour error over the window, the path from `path_from` on."""
    contour = contour_error(record, path_from)
    if contour is None:
        return None
    inside = contour.distance[window.mask(record.t)]
    return ContourMetrics(contour.axes, peak(inside), rms(inside))


def axis_summary(
    record: RunRecord,
    skip: float,
    approach: float = 0.0,
    failing: Sequence[str] = (),
    predictions: Sequence[PredictionComparison] = (),
    force_control: Sequence[DepthStretch] | None = None,
    drive: DriveFigures | None = None,
    start_stamp_ns: int | None = None,
) -> AxisSummary:
    """The summary of an axis job's record: figures over [approach + skip, end), each axis
    up to its stop (record.events); the events of a kind in `failing` fail the job."""
    window = Window(approach + skip)
    events = tuple(record.events)
    stops = first_stops(events)
    until = min((t for t, _ in stops.values()), default=None)
    contour_window = window if until is None else Window(window.start, until)
    return AxisSummary(
        skip=skip,
        approach=approach,
        window=window,
        axes=tuple(axis_figures(record, window, stops)),
        contour=contour_figures(record, contour_window, approach) if len(record.t) else None,
        contour_until=until,
        events=events,
        failures=tuple(e for e in events if e.kind in failing),
        predictions=tuple(predictions),
        force_control=None if force_control is None else tuple(force_control),
        job_end_time=float(record.t[-1]) if force_control is not None else None,
        drive=drive,
        start_stamp_ns=start_stamp_ns,
    )


@dataclass(frozen=True)
class ForceSummary:
    """The cutting-force job's summary (Rubio 2013): J_c of eq. (14) and the override."""

    j_c: float  # [N²·s]
    mean_override: float
    override_min: float
    override_max: float
    betas: tuple[float, ...]  # the β that were active, in order of first use
    beta_switches: int
    events: tuple[Event, ...] = ()
    failures: tuple[Event, ...] = ()

    def lines(self) -> list[str]:
        return [
            f'J_c (Rubio 2013 eq. 14) = {self.j_c:.6g} N²·s; override: mean '
            f'{self.mean_override:.4f}, range [{self.override_min:.4f}, '
            f'{self.override_max:.4f}]; active β: ' + ', '.join(f'{b:g}' for b in self.betas),
            *(e.text() for e in self.events),
        ]

    def text(self) -> str:
        return '\n'.join(self.lines())

    def to_json(self) -> dict[str, Any]:
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out['betas'] = list(self.betas)
        out['events'] = [e.to_json() for e in self.events]
        out['failures'] = [e.to_json() for e in self.failures]
        return out

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> ForceSummary:
        values = dict(d)
        values['betas'] = tuple(d['betas'])
        values['events'] = tuple(Event.from_json(e) for e in d['events'])
        values['failures'] = tuple(Event.from_json(e) for e in d['failures'])
        return cls(**values)


def force_summary(
    j_c: float, override: np.ndarray, beta: np.ndarray, events: Sequence[Event] = ()
) -> ForceSummary:
    known = override[np.isfinite(override)]  # none: a run that stopped before its first
    return ForceSummary(
        j_c=float(j_c),
        mean_override=float(np.mean(known)) if known.size else math.nan,
        override_min=float(np.min(known)) if known.size else math.nan,
        override_max=float(np.max(known)) if known.size else math.nan,
        betas=tuple(float(b) for b in dict.fromkeys(beta.tolist())),
        beta_switches=int(np.count_nonzero(np.diff(beta))),
        events=tuple(events),
    )


Summary = AxisSummary | ForceSummary
