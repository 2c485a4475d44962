"""Report: analyse one or more rosbag2 bags of mill runs; print a table, write Markdown and plots.

    report runs/slotting-X/bag                          # -> runs/slotting-X/report/report.md
    report adrc/bag pd/bag --out cmp --freqs 60,120     # two runs side by side

Per run and axis, over t >= --skip (the start transient excluded):

- tracking error e = measured position - reference: max |e|, RMS e, and the
  largest RMS of e over any window of --window seconds (a sustained error, where
  max |e| may be one sample);
- disturbance estimation error xi_hat - xi against the plant's ground truth;
- spectrum of e and of xi_hat - xi (Hann window) and their amplitudes at --freqs
  (single-frequency DFT, so a tone between FFT bins is not under-read);
- cutting force and commanded torque statistics; the feed override if the bag
  has /mill/feed_override;
- loop timing: the wall-clock period between consecutive samples as they were
  received (the recorder's publish time; jitter = its standard deviation) and
  the plant's lockstep wait for commands from its /diagnostics status.

max |e|, RMS e and the RMS of xi_hat - xi and of xi come from
`mill_bringup.metrics.summarize` on a RunRecord built by
`mill_bringup.run_record.build_record`: the code the runner uses for the summary it
prints, so both agree on the same run.

The bag is read by topic names and types only (see mill_bringup.run_record), so a
bag from `ros2 bag record` with these topics works too.
"""

from __future__ import annotations

import argparse
import datetime as dt
import math
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from mill_bag.errors import BagError

from mill_bringup.metrics import AxisMetrics, format_summary, summarize
from mill_bringup.run_record import BagRun, read_run

ZOOM = 0.1  # length of the zoomed time windows of the plots [s]


# -- metrics ---------------------------------------------------------------------------------


def max_window_rms(x: np.ndarray, width: int) -> float:
    """Largest RMS of x over `width` consecutive samples (windows with a gap are skipped)."""
    if width < 1 or x.size < width:
        return math.nan
    finite = np.isfinite(x)
    sq = np.where(finite, x * x, 0.0)
    c = np.concatenate(([0.0], np.cumsum(sq)))
    good = np.concatenate(([0], np.cumsum(finite)))
    sums = c[width:] - c[:-width]
    full = (good[width:] - good[:-width]) == width
    if not full.any():
        return math.nan
    return float(np.sqrt(max(sums[full].max(), 0.0) / width))


def finite_segment(t: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The longest run of finite samples of x (spectra need an unbroken record)."""
    ok = np.isfinite(x)
    if ok.all():
        return t, x
    best, start, best_range = 0, None, (0, 0)
    for i, good in enumerate(np.append(ok, False)):
        if good and start is None:
            start = i
        elif not good and start is not None:
            if i - start > best:
                best, best_range = i - start, (start, i)
            start = None
    a, b = best_range
    return t[a:b], x[a:b]


def amplitude_spectrum(x: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Single-sided amplitude spectrum, Hann window (a tone of amplitude A on a bin reads A)."""
    x = x - np.mean(x)
    w = np.hanning(x.size)
    spec = np.fft.rfft(x * w)
    amp = 2.0 * np.abs(spec) / w.sum()
    amp[0] /= 2.0
    return np.fft.rfftfreq(x.size, dt), amp


def amplitude_at(x: np.ndarray, dt: float, freq: float) -> float:
    """Amplitude of the component of x at `freq` [Hz]: Hann-windowed DFT evaluated at freq."""
    if x.size < 2:
        return math.nan
    x = x - np.mean(x)
    w = np.hanning(x.size)
    phase = np.exp(-2j * np.pi * freq * dt * np.arange(x.size))
    return float(2.0 * np.abs(np.sum(w * x * phase)) / w.sum())


@dataclass
class AxisReport:
    axis: str
    summary: AxisMetrics
    max_window_rms_error: float  # [m]
    max_disturbance_error: float  # max |xi_hat - xi| [m/s^2]
    error_amplitude: dict[float, float]  # |E(f)| [m]
    disturbance_error_amplitude: dict[float, float]  # |Xi_err(f)| [m/s^2]
    rms_torque: float
    max_torque: float
    force_mean: float
    force_std: float
    force_max: float


@dataclass
class RunReport:
    label: str
    run: BagRun
    skip: float
    window: float
    freqs: list[float]
    axes: list[AxisReport]
    loop: dict[str, float] = field(default_factory=dict)
    feed: dict[str, float] | None = None
    read_seconds: float = 0.0

    @property
    def summary(self) -> list[AxisMetrics]:
        return [a.summary for a in self.axes]


def _finite(x: np.ndarray) -> np.ndarray:
    return x[np.isfinite(x)]


def _stat(fn, x: np.ndarray) -> float:
    x = _finite(x)
    return float(fn(x)) if x.size else math.nan


def analyse(run: BagRun, label: str, skip: float, window: float, freqs: list[float]) -> RunReport:
    from mill_common.signals import AXES

    rec = run.record
    dt_s = run.dt_ns / 1e9
    after = rec.t >= skip
    t = rec.t[after]
    e = rec.tracking_error[after]
    d = rec.disturbance_error[after]
    tau = rec['torque'][after]
    force = rec['force'][after]
    width = max(1, round(window / dt_s))
    summary = {m.axis: m for m in summarize(rec, skip)}
    axes = []
    for axis in run.axes:
        i = AXES.index(axis)
        if axis not in summary:
            continue
        _, ei = finite_segment(t, e[:, i])
        _, di = finite_segment(t, d[:, i])
        axes.append(
            AxisReport(
                axis=axis,
                summary=summary[axis],
                max_window_rms_error=max_window_rms(e[:, i], width),
                max_disturbance_error=_stat(lambda v: np.max(np.abs(v)), d[:, i]),
                error_amplitude={f: amplitude_at(ei, dt_s, f) for f in freqs},
                disturbance_error_amplitude={f: amplitude_at(di, dt_s, f) for f in freqs},
                rms_torque=_stat(lambda v: np.sqrt(np.mean(v * v)), tau[:, i]),
                max_torque=_stat(lambda v: np.max(np.abs(v)), tau[:, i]),
                force_mean=_stat(np.mean, force[:, i]),
                force_std=_stat(np.std, force[:, i]),
                force_max=_stat(lambda v: np.max(np.abs(v)), force[:, i]),
            )
        )
    report = RunReport(label, run, skip, window, freqs, axes)
    report.loop = loop_timing(run)
    if run.feed_override:
        values = np.array([v for _, v in run.feed_override])
        report.feed = {
            'messages': float(values.size),
            'min': float(values.min()),
            'mean': float(values.mean()),
            'max': float(values.max()),
        }
    return report


def loop_timing(run: BagRun) -> dict[str, float]:
    out: dict[str, float] = {}
    if run.state_wall_ns is not None:
        w = run.state_wall_ns
        ok = (w[1:] > 0) & (w[:-1] > 0)
        periods = (w[1:] - w[:-1])[ok] / 1e6  # [ms]
        if periods.size:
            out.update(
                {
                    'period_mean_ms': float(periods.mean()),
                    'period_std_ms': float(periods.std()),
                    'period_p99_ms': float(np.percentile(periods, 99)),
                    'period_max_ms': float(periods.max()),
                    'steps_per_second': 1e3 / float(periods.mean()),
                }
            )
    status = run.plant_status
    for key, name in (('mean_wait_ms', 'wait_mean_ms'), ('max_wait_ms', 'wait_max_ms')):
        if key in status:
            out[name] = float(status[key])
    if 'step' in status and float(status.get('wall_s', 0)) > 0:
        out['plant_steps_per_second'] = float(status['step']) / float(status['wall_s'])
    return out


# -- text ------------------------------------------------------------------------------------


def _um(x: float) -> str:
    return f'{x * 1e6:.3f}' if math.isfinite(x) else 'n/a'


def _f(x: float, fmt: str = '.3f') -> str:
    return format(x, fmt) if x is not None and math.isfinite(x) else 'n/a'


def _hz(f: float) -> str:
    return f'{f:g} Hz'


def text_table(reports: list[RunReport]) -> str:
    lines = []
    for r in reports:
        lines.append(
            f'== {r.label}: {r.run.bag.path} ({r.run.n} samples, T = {r.run.dt_ns / 1e6:g} ms)'
        )
        lines.append(format_summary(r.summary, r.skip))
        head = f'axis   max RMS_{r.window:g}s e [um]'
        for f in r.freqs:
            head += f'   |E({_hz(f)})| [um]'
        head += '   RMS tau [N m]   mean F [N]   max |F| [N]'
        lines.append(head)
        for a in r.axes:
            row = f'{a.axis:>4}   {_um(a.max_window_rms_error):>19}'
            for f in r.freqs:
                row += f'   {_um(a.error_amplitude[f]):>{len(_hz(f)) + 9}}'
            row += (
                f'   {_f(a.rms_torque, ".4f"):>13}   {_f(a.force_mean, ".2f"):>10}'
                f'   {_f(a.force_max, ".2f"):>11}'
            )
            lines.append(row)
        lines.append(feed_text(r))
        lines.append(loop_text(r))
        for note in r.run.notes:
            lines.append(f'note: {note}')
    return '\n'.join(lines)


def feed_text(r: RunReport) -> str:
    if r.feed is None:
        return 'feed override: no feed override in this bag'
    f = r.feed
    return (
        f'feed override: {f["messages"]:.0f} messages, min {f["min"]:.3f}, '
        f'mean {f["mean"]:.3f}, max {f["max"]:.3f}'
    )


def loop_text(r: RunReport) -> str:
    lp = r.loop
    parts = []
    if 'period_mean_ms' in lp:
        parts.append(
            f'sample period (wall) mean {lp["period_mean_ms"]:.3f} ms, jitter (std) '
            f'{lp["period_std_ms"]:.3f} ms, p99 {lp["period_p99_ms"]:.3f} ms, '
            f'max {lp["period_max_ms"]:.1f} ms ({lp["steps_per_second"]:.0f} steps/s)'
        )
    else:
        parts.append('no wall-clock receive times in this bag')
    if 'wait_mean_ms' in lp:
        parts.append(
            f'lockstep wait for commands mean {lp["wait_mean_ms"]:.3f} ms, '
            f'max {lp["wait_max_ms"]:.1f} ms'
        )
    return 'loop timing: ' + '; '.join(parts)


def markdown(reports: list[RunReport], figures: list[tuple[str, str]], argv: list[str]) -> str:
    skip, window, freqs = reports[0].skip, reports[0].window, reports[0].freqs
    out = [
        '# mill run report',
        '',
        f'`report {" ".join(argv)}` on {dt.datetime.now():%Y-%m-%d %H:%M}. '
        f'Metrics over t ≥ {skip:g} s (the start transient excluded); e = measured position − '
        'reference; ξ is the lumped disturbance of Beltrán 2013 eq. (5), ξ̂ its estimate.',
        '',
        '## Bags',
        '',
        '| run | bag | samples | T | machine time | messages | size | per simulated second |'
        ' samples from |',
        '|---|---|---|---|---|---|---|---|---|',
    ]
    for r in reports:
        run = r.run
        sim = (run.n - 1) * run.dt_ns / 1e9
        per_s = run.size_bytes / sim / 1e6 if sim > 0 else math.nan
        out.append(
            f'| {r.label} | `{run.bag.path}` | {run.n} | {run.dt_ns / 1e6:g} ms | {sim:.3f} s '
            f'| {run.message_count} | {run.size_bytes / 1e6:.1f} MB | {per_s:.2f} MB '
            f'| {run.job_end_source} |'
        )
    notes = [(r.label, n) for r in reports for n in r.run.notes]
    if notes:
        out.append('')
        out += [f'- {label}: {note}' for label, note in notes]
    out += [
        '',
        '## Tracking and disturbance estimation',
        '',
        f'| run | axis | max \\|e\\| [µm] | RMS e [µm] | max RMS e over {window:g} s [µm] '
        '| RMS(ξ̂−ξ) [m/s²] | max \\|ξ̂−ξ\\| [m/s²] | RMS ξ [m/s²] |',
        '|---|---|---|---|---|---|---|---|',
    ]
    for r in reports:
        for a in r.axes:
            m = a.summary
            out.append(
                f'| {r.label} | {a.axis} | {_um(m.max_error)} | {_um(m.rms_error)} '
                f'| {_um(a.max_window_rms_error)} | {_f(m.rms_disturbance_error)} '
                f'| {_f(a.max_disturbance_error)} | {_f(m.rms_disturbance)} |'
            )
    out += [
        '',
        '## Error spectrum',
        '',
        'Amplitude of the tracking error and of the disturbance estimation error at the '
        'chosen frequencies (Hann window, single-frequency DFT over the analysed interval).',
        '',
        '| run | axis | '
        + ' | '.join(f'\\|E({_hz(f)})\\| [µm]' for f in freqs)
        + ' | '
        + ' | '.join(f'\\|(ξ̂−ξ)({_hz(f)})\\| [m/s²]' for f in freqs)
        + ' |',
        '|---|---|' + '---|' * (2 * len(freqs)),
    ]
    for r in reports:
        for a in r.axes:
            out.append(
                f'| {r.label} | {a.axis} | '
                + ' | '.join(_um(a.error_amplitude[f]) for f in freqs)
                + ' | '
                + ' | '.join(_f(a.disturbance_error_amplitude[f]) for f in freqs)
                + ' |'
            )
    out += [
        '',
        '## Cutting force and commanded torque',
        '',
        '| run | axis | mean F [N] | std F [N] | max \\|F\\| [N] | RMS τ [N·m] '
        '| max \\|τ\\| [N·m] |',
        '|---|---|---|---|---|---|---|',
    ]
    for r in reports:
        for a in r.axes:
            out.append(
                f'| {r.label} | {a.axis} | {_f(a.force_mean, ".2f")} | {_f(a.force_std, ".2f")} '
                f'| {_f(a.force_max, ".2f")} | {_f(a.rms_torque, ".4f")} '
                f'| {_f(a.max_torque, ".4f")} |'
            )
    out += ['', '## Feed override', '']
    out += [f'- {r.label}: {feed_text(r).removeprefix("feed override: ")}' for r in reports]
    out += [
        '',
        '## Loop timing',
        '',
        'Sample period: wall-clock time between the arrivals of consecutive samples of the '
        'first state topic at the recorder (MCAP publish time); jitter is its standard '
        'deviation. Lockstep wait: the time the plant waited for all commands of a step '
        '(its /diagnostics status).',
        '',
        '| run | mean period [ms] | jitter [ms] | p99 [ms] | max [ms] | steps/s '
        '| mean wait [ms] | max wait [ms] |',
        '|---|---|---|---|---|---|---|---|',
    ]
    for r in reports:
        lp = r.loop
        out.append(
            f'| {r.label} | {_f(lp.get("period_mean_ms", math.nan))} '
            f'| {_f(lp.get("period_std_ms", math.nan))} | {_f(lp.get("period_p99_ms", math.nan))} '
            f'| {_f(lp.get("period_max_ms", math.nan), ".1f")} '
            f'| {_f(lp.get("steps_per_second", math.nan), ".0f")} '
            f'| {_f(lp.get("wait_mean_ms", math.nan))} '
            f'| {_f(lp.get("wait_max_ms", math.nan), ".1f")} |'
        )
    out += ['', '## Figures', '']
    for name, caption in figures:
        out += [f'### {caption}', '', f'![{caption}]({name})', '']
    return '\n'.join(out)


# -- plots -----------------------------------------------------------------------------------


def _scale(values: np.ndarray, unit: str) -> tuple[float, str]:
    """(factor, unit) that shows metres (or m/s^2...) in readable numbers."""
    peak = np.nanmax(np.abs(values)) if np.isfinite(values).any() else 0.0
    if unit == 'm':
        if peak >= 1e-3:
            return 1e3, 'mm'
        return 1e6, 'µm'
    return 1.0, unit


def envelope(t: np.ndarray, y: np.ndarray, bins: int = 2000) -> tuple[np.ndarray, np.ndarray]:
    """Min/max decimation for plotting: per bin of samples its minimum and maximum, so a
    dense signal looks the same with 2 points per bin (about a pixel column)."""
    n = y.size
    if n <= 4 * bins or not np.isfinite(y).all():
        return t, y
    edges = np.linspace(0, n, bins + 1).astype(int)[:-1]
    lo = np.minimum.reduceat(y, edges)
    hi = np.maximum.reduceat(y, edges)
    tm = t[edges]
    return np.repeat(tm, 2), np.column_stack((lo, hi)).ravel()


def log_envelope(f: np.ndarray, a: np.ndarray, bins: int = 1200) -> tuple[np.ndarray, np.ndarray]:
    """Min/max decimation of a spectrum over log-spaced frequency bins (for a log axis)."""
    if f.size <= 4 * bins:
        return f, a
    edges = np.unique(np.geomspace(1, f.size, bins).astype(int) - 1)
    lo = np.minimum.reduceat(a, edges)
    hi = np.maximum.reduceat(a, edges)
    return np.repeat(f[edges], 2), np.column_stack((lo, hi)).ravel()


def plot_all(reports: list[RunReport], out: Path, workers: int = 1) -> list[tuple[str, str]]:
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from matplotlib.ticker import LogLocator, NullFormatter

    plt.rcParams.update(
        {
            'figure.dpi': 100,
            'savefig.dpi': 110,
            'axes.grid': True,
            'grid.alpha': 0.3,
            'font.size': 9,
            'axes.titlesize': 10,
            'legend.fontsize': 8,
            'path.simplify_threshold': 0.5,
        }
    )
    from mill_common.signals import AXES

    cols = len(reports)
    axes_names = reports[0].run.axes

    def grid(rows: int, height: float = 2.3):
        fig, ax = plt.subplots(
            rows,
            cols,
            figsize=(5.2 * cols + 1.0, height * rows + 0.8),
            squeeze=False,
            sharex='col',
            layout='constrained',
        )
        return fig, ax

    jobs: list[tuple[str, str, Callable[[], Any]]] = []  # (file, caption, make figure)

    def figure(name: str, caption: str):
        def register(make):
            jobs.append((name, caption, make))
            return make

        return register

    def per_axis(name, caption, title, draw):
        def make():
            fig, ax = grid(len(axes_names))
            for c, r in enumerate(reports):
                for row, axis in enumerate(axes_names):
                    a = ax[row, c]
                    i = AXES.index(axis)
                    ylabel = draw(a, r, i)
                    a.set_title(f'{r.label}: {axis} axis', loc='left')
                    a.set_ylabel(ylabel)
                    if row == len(axes_names) - 1:
                        a.set_xlabel('time t [s]')
            fig.suptitle(title)
            return fig

        jobs.append((name, caption, make))

    def draw_position(a, r, i):
        rec = r.run.record
        a.plot(
            *envelope(rec.t, rec['position'][:, i] * 1e3), 'C0', lw=1.2, label='measured position'
        )
        a.plot(*envelope(rec.t, rec['reference'][:, i] * 1e3), 'k--', lw=1.0, label='reference')
        a.legend(loc='best')
        return 'position [mm]'

    per_axis(
        'position.png',
        'Reference and measured position',
        'Reference and measured position per axis',
        draw_position,
    )

    def draw_error(a, r, i):
        rec = r.run.record
        e = rec.tracking_error[:, i]
        k, unit = _scale(e[rec.t >= r.skip], 'm')
        a.plot(*envelope(rec.t, e * k), color='C3', lw=0.8, label='e = position − reference')
        a.axvspan(0, r.skip, color='0.85', alpha=0.5, label=f'excluded (t < {r.skip:g} s)')
        finite = e[rec.t >= r.skip]
        if np.isfinite(finite).any():
            lim = np.nanmax(np.abs(finite)) * k * 1.15
            a.set_ylim(-lim, lim)
        a.legend(loc='upper right')
        return f'tracking error [{unit}]'

    per_axis('tracking_error.png', 'Tracking error', 'Tracking error per axis', draw_error)

    def draw_torque(a, r, i):
        rec = r.run.record
        a.plot(*envelope(rec.t, rec['torque'][:, i]), 'C2', lw=0.8, label='commanded torque τ')
        a.legend(loc='upper right')
        return 'torque [N·m]'

    per_axis('torque.png', 'Commanded torque', 'Commanded motor torque per axis', draw_torque)

    def draw_disturbance(a, r, i):
        rec = r.run.record
        a.plot(
            *envelope(rec.t, rec['true_disturbance'][:, i]), 'k', lw=0.7, label='ξ (plant, true)'
        )
        a.plot(
            *envelope(rec.t, rec['estimate_disturbance'][:, i]),
            color='C1',
            lw=0.7,
            alpha=0.8,
            label='ξ̂ (observer estimate)',
        )
        a.legend(loc='upper right', ncols=2)
        return 'ξ [m/s²]'

    per_axis(
        'disturbance.png',
        'Disturbance and its estimate',
        'Lumped disturbance ξ and the observer estimate ξ̂ per axis',
        draw_disturbance,
    )

    def zoom_window(r: RunReport) -> tuple[float, float]:
        rec = r.run.record
        t_end = rec.t[-1]
        t0 = max(r.skip, 0.5 * (r.skip + t_end))
        force = np.abs(rec['force'])
        cutting = np.nonzero((rec.t >= t0) & np.isfinite(force).all(axis=1) & (force.sum(1) > 0))
        if cutting[0].size:
            t0 = rec.t[cutting[0][0]]
        return t0, min(t0 + ZOOM, t_end)

    def draw_disturbance_zoom(a, r, i):
        rec = r.run.record
        t0, t1 = zoom_window(r)
        sel = (rec.t >= t0) & (rec.t <= t1)
        a.plot(rec.t[sel], rec['true_disturbance'][sel, i], 'k', lw=1.0, label='ξ (plant, true)')
        a.plot(rec.t[sel], rec['estimate_disturbance'][sel, i], 'C1', lw=1.0, label='ξ̂ (estimate)')
        a.plot(rec.t[sel], rec.disturbance_error[sel, i], 'C4', lw=0.8, ls=':', label='ξ̂ − ξ')
        a.legend(loc='upper right', ncols=3)
        return 'ξ [m/s²]'

    per_axis(
        'disturbance_zoom.png',
        f'Disturbance and its estimate, {ZOOM * 1e3:g} ms while cutting',
        f'ξ, ξ̂ and ξ̂ − ξ over {ZOOM * 1e3:g} ms while cutting',
        draw_disturbance_zoom,
    )

    @figure('cutting_force.png', 'Cutting forces')
    def _force():  # full run and a zoom, one row per run
        fig, ax = plt.subplots(
            cols, 2, figsize=(12, 2.8 * cols + 0.8), squeeze=False, layout='constrained'
        )
        for row, r in enumerate(reports):
            rec = r.run.record
            t0, t1 = zoom_window(r)
            sel = (rec.t >= t0) & (rec.t <= t1)
            for j, name in enumerate(('F_x', 'F_y', 'F_z')):
                ax[row, 0].plot(
                    *envelope(rec.t, rec['force'][:, j]), lw=0.6, color=f'C{j}', label=f'${name}$'
                )
                ax[row, 1].plot(
                    rec.t[sel], rec['force'][sel, j], lw=1.0, color=f'C{j}', label=f'${name}$'
                )
            ax[row, 0].set_title(f'{r.label}: cutting force on the tool', loc='left')
            ax[row, 1].set_title(f'{r.label}: {ZOOM * 1e3:g} ms from t = {t0:.2f} s', loc='left')
            for a in ax[row]:
                a.set_xlabel('time t [s]')
                a.set_ylabel('force [N]')
                a.legend(loc='upper right', ncols=3)
        fig.suptitle('Cutting forces (Kline model, sign of Beltrán 2013 eq. 1)')
        return fig

    def _contour():
        fig, ax = plt.subplots(
            2, cols, figsize=(5.2 * cols + 1.0, 9.0), squeeze=False, layout='constrained'
        )
        for c, r in enumerate(reports):
            rec = r.run.record
            x, y = rec['position'][:, 0], rec['position'][:, 1]
            xr, yr = rec['reference'][:, 0], rec['reference'][:, 1]
            a = ax[0, c]
            a.plot(xr * 1e3, yr * 1e3, 'k--', lw=1.0, label='reference path')
            a.plot(x * 1e3, y * 1e3, 'C0', lw=1.2, label='measured path')
            a.set_title(f'{r.label}: x–y contour of the cut', loc='left')
            a.set_aspect('equal', adjustable='datalim')
            a.legend(loc='best')
            a = ax[1, c]
            after = rec.t >= r.skip
            dev = np.hypot(x - xr, y - yr)[after]
            extent = max(np.nanmax(xr) - np.nanmin(xr), np.nanmax(yr) - np.nanmin(yr), 1e-9)
            peak = np.nanmax(dev) if np.isfinite(dev).any() else 0.0
            gain = _nice(0.05 * extent / peak) if peak > 0 else 1.0
            a.plot(xr * 1e3, yr * 1e3, color='0.6', lw=1.0, label='reference path')
            a.plot(
                (xr + gain * (x - xr))[after] * 1e3,
                (yr + gain * (y - yr))[after] * 1e3,
                'C3',
                lw=0.8,
                label=f'measured, deviation × {gain:g}',
            )
            a.set_title(
                f'{r.label}: contour deviation magnified × {gain:g} (t ≥ {r.skip:g} s)', loc='left'
            )
            a.set_aspect('equal', adjustable='datalim')
            a.legend(loc='best')
            for a in ax[:, c]:
                a.set_xlabel('x [mm]')
                a.set_ylabel('y [mm]')
        return fig

    if 'x' in axes_names and 'y' in axes_names:
        jobs.append(('contour.png', 'x–y contour of the cut', _contour))

    @figure('error_spectrum.png', 'Error spectrum')
    def _spectrum():  # one row per axis, runs overlaid
        fig, ax = plt.subplots(
            len(axes_names),
            2,
            figsize=(12, 2.6 * len(axes_names) + 0.8),
            squeeze=False,
            layout='constrained',
        )
        for row, axis in enumerate(axes_names):
            i = AXES.index(axis)
            for c, r in enumerate(reports):
                rec = r.run.record
                after = rec.t >= r.skip
                for col, (signal, scale) in enumerate(
                    ((rec.tracking_error[after, i], 1e6), (rec.disturbance_error[after, i], 1.0))
                ):
                    _, seg = finite_segment(rec.t[after], signal)
                    if seg.size < 16:
                        continue
                    f, amp = amplitude_spectrum(seg, r.run.dt_ns / 1e9)
                    ax[row, col].loglog(
                        *log_envelope(f[1:], amp[1:] * scale), lw=0.6, color=f'C{c}', label=r.label
                    )
            for col, what in enumerate(('tracking error e [µm]', 'ξ̂ − ξ [m/s²]')):
                a = ax[row, col]
                # decades only: minor tick labels on 10 decades cost seconds to lay out
                for axis_ in (a.xaxis, a.yaxis):
                    axis_.set_major_locator(LogLocator(numticks=8))
                    axis_.set_minor_locator(LogLocator(subs=(2, 5), numticks=8))
                    axis_.set_minor_formatter(NullFormatter())
                for fr in reports[0].freqs:
                    a.axvline(fr, color='0.4', ls=':', lw=0.8)
                a.set_title(f'{axis} axis: amplitude spectrum of {what.split(" [")[0]}', loc='left')
                a.set_ylabel(f'amplitude [{what.split("[")[1]}')
                a.set_xlabel('frequency [Hz]')
                if a.lines:
                    a.legend(
                        loc='lower left',
                        title=f'dotted: {", ".join(_hz(f) for f in reports[0].freqs)}',
                    )
        fig.suptitle('Error spectra (Hann window, t ≥ skip)')
        return fig

    with_wall = [r for r in reports if r.run.state_wall_ns is not None]

    def _timing():
        fig, ax = plt.subplots(1, 1, figsize=(7, 3.6), layout='constrained')
        for c, r in enumerate(with_wall):
            w = r.run.state_wall_ns
            ok = (w[1:] > 0) & (w[:-1] > 0)
            periods = (w[1:] - w[:-1])[ok] / 1e6
            if periods.size:
                top = np.percentile(periods, 99.9)
                bins = np.linspace(0, max(top, 1e-3), 80)
                ax.hist(
                    np.clip(periods, 0, top),
                    bins=bins,
                    histtype='step',
                    color=f'C{c}',
                    label=r.label,
                )
        ax.set_yscale('log')
        ax.set_xlabel('wall-clock time between consecutive samples [ms] (clipped at p99.9)')
        ax.set_ylabel('samples')
        ax.set_title('Loop timing: sample period as received by the recorder', loc='left')
        ax.legend()
        return fig

    if with_wall:
        jobs.append(('loop_timing.png', 'Loop timing', _timing))
    return render(jobs, out, workers)


_JOBS: list = []


def _render(i: int) -> None:
    import matplotlib.pyplot as plt

    name, _caption, make, out = _JOBS[i]
    fig = make()
    fig.savefig(out / name)
    plt.close(fig)


def render(jobs: list, out: Path, workers: int) -> list[tuple[str, str]]:
    """Draw and save the figures, in `workers` forked processes if more than one."""
    global _JOBS  # read by the forked workers
    _JOBS = [(*job, out) for job in jobs]
    try:
        if workers > 1 and len(jobs) > 1:
            import multiprocessing

            with multiprocessing.get_context('fork').Pool(workers) as pool:
                pool.map(_render, range(len(jobs)), chunksize=1)
        else:
            for i in range(len(jobs)):
                _render(i)
    finally:
        _JOBS = []
    return [(name, caption) for name, caption, _ in jobs]


def _nice(x: float) -> float:
    """The largest of 1, 2, 5 x 10^n not above x (at least 1)."""
    if not x > 1:
        return 1.0
    exp = math.floor(math.log10(x))
    for m in (5, 2, 1):
        if m * 10**exp <= x:
            return float(m * 10**exp)
    return float(10**exp)


# -- command line ----------------------------------------------------------------------------


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, no usage block
        print(f'{self.prog}: error: {message}', file=sys.stderr)
        raise SystemExit(2)


def _freqs(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(',') if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f'--freqs {text!r}: not a list of numbers') from None
    if not values or any(not (math.isfinite(v) and v > 0) for v in values):
        raise argparse.ArgumentTypeError(f'--freqs {text!r}: frequencies must be > 0')
    return values


def _positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text!r} is not a number') from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f'{text!r} must be > 0')
    return value


def _non_negative(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text!r} is not a number') from None
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f'{text!r} must be >= 0')
    return value


def labels_for(paths: list[Path]) -> list[str]:
    """Short distinct names: the bag directory, or its run directory for RUN/bag."""
    labels = []
    for p in paths:
        p = p.resolve()
        name = p.stem if p.is_file() else p.name
        if name == 'bag' or p.is_file():
            name = p.parent.name if name == 'bag' else name
        labels.append(name)
    if len(set(labels)) < len(labels):
        labels = [f'{i + 1}:{label}' for i, label in enumerate(labels)]
    return labels


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = _Parser(
        prog='report',
        description='Analyse rosbag2 bags of mill runs: print a table, write DIR/report.md '
        'and PNG plots. Several bags are compared side by side.',
    )
    parser.add_argument('bags', nargs='+', type=Path, metavar='BAG', help='bag directory or .mcap')
    parser.add_argument('--out', type=Path, help='output directory (default: BAG/../report)')
    parser.add_argument(
        '--skip', type=_non_negative, default=1.0, help='metrics over t >= SKIP [s] (default 1)'
    )
    parser.add_argument(
        '--freqs',
        type=_freqs,
        default=[60.0, 120.0],
        help='frequencies for the error amplitudes [Hz], comma separated (default 60,120)',
    )
    parser.add_argument(
        '--window',
        type=_positive,
        default=0.1,
        help='window of the largest windowed RMS tracking error [s] (default 0.1)',
    )
    parser.add_argument('--label', action='append', help='name of each bag in the report')
    parser.add_argument('--no-plots', action='store_true', help='table and report.md only')
    args = parser.parse_args(argv)
    if args.label and len(args.label) != len(args.bags):
        parser.error(f'{len(args.label)} --label for {len(args.bags)} bags')
    labels = args.label or labels_for(args.bags)
    reports = []
    t_start = time.monotonic()
    for bag, label in zip(args.bags, labels, strict=True):
        t0 = time.monotonic()
        try:
            run = read_run(bag)
        except BagError as exc:
            print(f'report: error: {exc}', file=sys.stderr)
            return 1
        except OSError as exc:
            print(f'report: error: {bag}: {exc.strerror or exc}', file=sys.stderr)
            return 1
        except Exception as exc:  # a damaged message in an otherwise readable bag
            print(
                f'report: error: {bag}: cannot read ({type(exc).__name__}: {exc})', file=sys.stderr
            )
            return 1
        if run.n <= 1 or not (run.record.t >= args.skip).any():
            print(
                f'report: error: {bag}: no samples at t >= {args.skip:g} s '
                f'(the run lasts {run.record.t[-1]:g} s)',
                file=sys.stderr,
            )
            return 1
        report = analyse(run, label, args.skip, args.window, args.freqs)
        report.read_seconds = time.monotonic() - t0
        reports.append(report)
    out = args.out or (args.bags[0].resolve().parent / 'report')
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        print(f'report: error: cannot create {out}: {exc.strerror}', file=sys.stderr)
        return 1
    big = sum(r.run.n for r in reports) > 20_000
    workers = min(2, os.cpu_count() or 1) if big else 1
    figures = [] if args.no_plots else plot_all(reports, out, workers)
    (out / 'report.md').write_text(markdown(reports, figures, argv) + '\n')
    print(text_table(reports))
    print(
        f'report {out / "report.md"} with {len(figures)} plots ({time.monotonic() - t_start:.1f} s)'
    )
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
