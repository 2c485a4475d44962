"""The figures of a report, one PNG each; several runs side by side (one column per run).

`plot_all` draws every figure the runs' data allow and returns their (file, caption)
for report.md. `figures` lists them in report order, each a `Plot` whose `make` draws
it: one function per figure (`per_axis_figure` with a `draw_*` per quantity for the
time plots, `cutting_force_figure`, `contour_figure`, `spectrum_figure`,
`loop_timing_figure`), all laid out by `_layout`. For long runs (`workers` > 1)
`render` draws them in forked processes: matplotlib's layout, not the data, is what
takes the time. Dense signals are min/max-decimated (`envelope`), so a plot looks
the same with about two points per pixel column. matplotlib is imported on first
use, so `report --no-plots` never loads it.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from mill_common.signals import AXES

from mill_analysis.report.analysis import RunReport, amplitude_spectrum, finite_segment
from mill_analysis.report.text import hz

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

ZOOM = 0.1  # length of the zoomed time windows of the plots [s]
STYLE = {
    'figure.dpi': 100,
    'savefig.dpi': 110,
    'axes.grid': True,
    'grid.alpha': 0.3,
    'font.size': 9,
    'axes.titlesize': 10,
    'legend.fontsize': 8,
    'path.simplify_threshold': 0.5,
}

Draw = Callable[['Axes', RunReport, int], str]  # one axis (index i) of a run; -> y label


@dataclass(frozen=True)
class Plot:
    """One figure of the report, drawn when `make` is called (by `render`)."""

    name: str  # file name in the output directory
    caption: str  # heading and alt text in report.md
    make: Callable[[], Figure]  # draws the figure


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
    """Draw every figure the runs allow into `out`; (file, caption) of each, in report order."""
    styled_pyplot()
    return render(figures(reports), out, workers)


def figures(reports: list[RunReport]) -> list[Plot]:
    """The figures of a report, in the order of report.md; none is drawn yet."""
    zoom_ms = f'{ZOOM * 1e3:g} ms'

    def per_axis(name: str, caption: str, title: str, draw: Draw) -> Plot:
        return Plot(name, caption, partial(per_axis_figure, reports, title, draw))

    jobs = [
        per_axis(
            'position.png',
            'Reference and measured position',
            'Reference and measured position per axis',
            draw_position,
        ),
        per_axis('tracking_error.png', 'Tracking error', 'Tracking error per axis', draw_error),
        per_axis('torque.png', 'Commanded torque', 'Commanded motor torque per axis', draw_torque),
        per_axis(
            'disturbance.png',
            'Disturbance and its estimate',
            'Lumped disturbance ξ and the observer estimate ξ̂ per axis',
            draw_disturbance,
        ),
        per_axis(
            'disturbance_zoom.png',
            f'Disturbance and its estimate, {zoom_ms} while cutting',
            f'ξ, ξ̂ and ξ̂ − ξ over {zoom_ms} while cutting',
            draw_disturbance_zoom,
        ),
        Plot('cutting_force.png', 'Cutting forces', partial(cutting_force_figure, reports)),
    ]
    axes = reports[0].run.axes
    if 'x' in axes and 'y' in axes:
        jobs.append(
            Plot(
                'contour.png',
                'Programmed path, measured contour and contour error',
                partial(contour_figure, reports),
            )
        )
    jobs.append(Plot('error_spectrum.png', 'Error spectrum', partial(spectrum_figure, reports)))
    with_wall = [r for r in reports if r.run.state_wall_ns is not None]
    if with_wall:
        jobs.append(Plot('loop_timing.png', 'Loop timing', partial(loop_timing_figure, with_wall)))
    realtime = [r for r in reports if r.run.realtime]
    if realtime:
        jobs.append(
            Plot(
                'command_latency.png',
                'State → command latency (realtime)',
                partial(latency_figure, realtime),
            )
        )
    return jobs


# -- layout ----------------------------------------------------------------------------------


def _pyplot() -> Any:
    """matplotlib.pyplot on the Agg backend (files only, no display)."""
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    return plt


def styled_pyplot() -> Any:
    """matplotlib.pyplot with the report's style (also the README image's)."""
    plt = _pyplot()
    plt.rcParams.update(STYLE)
    return plt


def _layout(
    rows: int, cols: int, width: float, height: float, **kwargs: Any
) -> tuple[Figure, np.ndarray]:
    """A width x height [in] figure with a rows x cols array of axes (2-D even for one)."""
    return _pyplot().subplots(
        rows, cols, figsize=(width, height), squeeze=False, layout='constrained', **kwargs
    )


def _run_columns_width(reports: list[Any]) -> float:
    """Width of a figure with one column per run [in]."""
    return 5.2 * len(reports) + 1.0


# -- time plots: one row per axis, one column per run ----------------------------------------


def per_axis_figure(reports: list[RunReport], title: str, draw: Draw) -> Figure:
    return axis_grid_figure(
        [r.label for r in reports],
        reports[0].run.axes,
        title,
        lambda a, c, i: draw(a, reports[c], i),
    )


def axis_grid_figure(
    labels: list[str], axes: list[str], title: str, draw: Callable[[Axes, int, int], str]
) -> Figure:
    """One row per axis, one column per label; draw(a, column, axis index) -> y label."""
    fig, ax = _layout(
        len(axes), len(labels), _run_columns_width(labels), 2.3 * len(axes) + 0.8, sharex='col'
    )
    for c, label in enumerate(labels):
        for row, axis in enumerate(axes):
            a = ax[row, c]
            ylabel = draw(a, c, AXES.index(axis))
            a.set_title(f'{label}: {axis} axis', loc='left')
            a.set_ylabel(ylabel)
            if row == len(axes) - 1:
                a.set_xlabel('time t [s]')
    fig.suptitle(title)
    return fig


def draw_position(a: Axes, r: RunReport, i: int) -> str:
    rec = r.run.record
    a.plot(*envelope(rec.t, rec['position'][:, i] * 1e3), 'C0', lw=1.2, label='measured position')
    a.plot(*envelope(rec.t, rec['reference'][:, i] * 1e3), 'k--', lw=1.0, label='reference')
    a.legend(loc='best')
    return 'position [mm]'


def draw_error(a: Axes, r: RunReport, i: int) -> str:
    rec = r.run.record
    return draw_tracking_error(a, rec.t, rec.tracking_error[:, i], r.skip)


def draw_tracking_error(a: Axes, t: np.ndarray, e: np.ndarray, skip: float) -> str:
    """e = position − reference [m] against t, scaled to µm or mm, t < skip greyed."""
    k, unit = _scale(e[t >= skip], 'm')
    a.plot(*envelope(t, e * k), color='C3', lw=0.8, label='e = position − reference')
    a.axvspan(0, skip, color='0.85', alpha=0.5, label=f'excluded (t < {skip:g} s)')
    finite = e[t >= skip]
    if np.isfinite(finite).any():
        lim = np.nanmax(np.abs(finite)) * k * 1.15
        a.set_ylim(-lim, lim)
    a.legend(loc='upper right')
    return f'tracking error [{unit}]'


def draw_torque(a: Axes, r: RunReport, i: int) -> str:
    rec = r.run.record
    a.plot(*envelope(rec.t, rec['torque'][:, i]), 'C2', lw=0.8, label='commanded torque τ')
    a.legend(loc='upper right')
    return 'torque [N·m]'


def draw_disturbance(a: Axes, r: RunReport, i: int) -> str:
    rec = r.run.record
    a.plot(*envelope(rec.t, rec['true_disturbance'][:, i]), 'k', lw=0.7, label='ξ (plant, true)')
    a.plot(
        *envelope(rec.t, rec['estimate_disturbance'][:, i]),
        color='C1',
        lw=0.7,
        alpha=0.8,
        label='ξ̂ (observer estimate)',
    )
    a.legend(loc='upper right', ncols=2)
    return 'ξ [m/s²]'


def zoom_window(r: RunReport) -> tuple[float, float]:
    """ZOOM seconds from the first cutting sample in the second half of the analysed time."""
    rec = r.run.record
    t_end = rec.t[-1]
    t0 = max(r.skip, 0.5 * (r.skip + t_end))
    force = np.abs(rec['force'])
    cutting = np.nonzero((rec.t >= t0) & np.isfinite(force).all(axis=1) & (force.sum(1) > 0))
    if cutting[0].size:
        t0 = rec.t[cutting[0][0]]
    return t0, min(t0 + ZOOM, t_end)


def draw_disturbance_zoom(a: Axes, r: RunReport, i: int) -> str:
    rec = r.run.record
    t0, t1 = zoom_window(r)
    sel = (rec.t >= t0) & (rec.t <= t1)
    a.plot(rec.t[sel], rec['true_disturbance'][sel, i], 'k', lw=1.0, label='ξ (plant, true)')
    a.plot(rec.t[sel], rec['estimate_disturbance'][sel, i], 'C1', lw=1.0, label='ξ̂ (estimate)')
    a.plot(rec.t[sel], rec.disturbance_error[sel, i], 'C4', lw=0.8, ls=':', label='ξ̂ − ξ')
    a.legend(loc='upper right', ncols=3)
    return 'ξ [m/s²]'


# -- the other figures -----------------------------------------------------------------------


def cutting_force_figure(reports: list[RunReport]) -> Figure:
    """The whole run and a zoom, one row per run."""
    fig, ax = _layout(len(reports), 2, 12, 2.8 * len(reports) + 0.8)
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


def contour_figure(reports: list[RunReport]) -> Figure:
    """Per run (column): the path against the reference path and the contour error magnified,
    in the x-y plane and, if the path moves in z, the side view (`planes`); then the contour
    error and the tracking error |e| over time."""
    planes = sorted({p for r in reports for p in contour_planes(r)})
    fig, ax = _layout(
        2 * len(planes) + 1, len(reports), _run_columns_width(reports), 8.0 * len(planes) + 3.0
    )
    for c, r in enumerate(reports):
        for row, (i, j) in enumerate(planes):
            _draw_contour(ax[2 * row, c], r, i, j)
            _draw_contour_deviation(ax[2 * row + 1, c], r, i, j)
            for a in ax[2 * row : 2 * row + 2, c]:
                a.set_xlabel(f'{AXES[i]} [mm]')
                a.set_ylabel(f'{AXES[j]} [mm]')
        _draw_contour_error(ax[-1, c], r)
    fig.suptitle('Programmed path and measured contour')
    return fig


def contour_planes(r: RunReport) -> list[tuple[int, int]]:
    """The views of the path: x-y (the part seen from above), and the side view along the
    longer of its x and y extents when the reference moves in z by more than 1 % of that:
    a plunge, a ramp or a 3-D contour, which the top view would hide."""
    ref = r.run.record['reference']
    extent = np.nanmax(ref, axis=0) - np.nanmin(ref, axis=0)
    planes = [(0, 1)]
    if 'z' in r.run.axes and extent[2] > 0.01 * max(extent[0], extent[1]):
        planes.append((0, 2) if extent[0] >= extent[1] else (1, 2))
    return planes


def _draw_contour(a: Axes, r: RunReport, i: int, j: int) -> None:
    """The measured path over the reference path [mm] in the plane (i, j), the whole run."""
    pos, ref = r.run.record['position'] * 1e3, r.run.record['reference'] * 1e3
    a.plot(ref[:, i], ref[:, j], 'k--', lw=1.0, label='reference (programmed) path')
    a.plot(pos[:, i], pos[:, j], 'C0', lw=1.2, label='measured contour')
    a.set_title(f'{r.label}: {AXES[i]}–{AXES[j]} contour of the cut', loc='left')
    a.set_aspect('equal', adjustable='datalim')
    a.legend(loc='best')


def _draw_contour_deviation(a: Axes, r: RunReport, i: int, j: int) -> None:
    """The measured contour with its contour error (from the nearest point of the path)
    magnified (1, 2, 5 x 10^n) to about 5 % of the path's extent, as a ballbar plot shows it."""
    rec, c = r.run.record, r.contour
    ref = rec['reference']
    a.plot(ref[:, i] * 1e3, ref[:, j] * 1e3, color='0.6', lw=1.0, label='reference path')
    if c is not None:
        after = rec.t >= r.skip
        near, pos = c.nearest[after], rec['position'][after]
        extent = np.nanmax(np.nanmax(ref, axis=0) - np.nanmin(ref, axis=0))
        peak = np.nanmax(c.distance[after]) if np.isfinite(c.distance[after]).any() else 0.0
        gain = _nice(0.05 * extent / peak) if peak > 0 else 1.0
        shown = near + gain * (pos - near)
        a.plot(
            shown[:, i] * 1e3,
            shown[:, j] * 1e3,
            'C3',
            lw=0.8,
            label=f'measured, contour error × {gain:g}',
        )
        a.set_title(f'{r.label}: contour error magnified × {gain:g} (t ≥ {r.skip:g} s)', loc='left')
    a.set_aspect('equal', adjustable='datalim')
    a.legend(loc='best')


def _draw_contour_error(a: Axes, r: RunReport) -> None:
    """The contour error and the tracking error |e| over time: their difference is the lag
    along the path."""
    rec, c = r.run.record, r.contour
    if c is None:
        return
    cols = [AXES.index(x) for x in c.axes]
    e = np.linalg.norm(rec.tracking_error[:, cols], axis=1)
    after = rec.t >= r.skip
    k, unit = _scale(e[after], 'm')
    a.plot(*envelope(rec.t, e * k), color='0.5', lw=0.8, label='tracking error |e|')
    a.plot(*envelope(rec.t, c.distance * k), 'C3', lw=0.8, label='contour error')
    a.axvspan(0, r.skip, color='0.85', alpha=0.5, label=f'excluded (t < {r.skip:g} s)')
    if np.isfinite(e[after]).any():
        a.set_ylim(0, np.nanmax(e[after]) * k * 1.15)
    a.set_title(f'{r.label}: contour error and tracking error', loc='left')
    a.set_xlabel('time t [s]')
    a.set_ylabel(f'error [{unit}]')
    a.legend(loc='upper right')


SPECTRA = ('tracking error e [µm]', 'ξ̂ − ξ [m/s²]')  # the columns of the spectrum figure


def spectrum_figure(reports: list[RunReport]) -> Figure:
    """One row per axis: the amplitude spectra of e and of xi_hat - xi, runs overlaid."""
    axes = reports[0].run.axes
    fig, ax = _layout(len(axes), 2, 12, 2.6 * len(axes) + 0.8)
    for row, axis in enumerate(axes):
        i = AXES.index(axis)
        for c, r in enumerate(reports):
            _draw_spectra(ax[row], r, i, f'C{c}')
        for col, what in enumerate(SPECTRA):
            _style_spectrum(ax[row, col], axis, what, reports[0].freqs)
    fig.suptitle('Error spectra (Hann window, t ≥ skip)')
    return fig


def _draw_spectra(ax_row: np.ndarray, r: RunReport, i: int, color: str) -> None:
    """The spectra of e [µm] and of xi_hat - xi [m/s^2] of one run and axis, t >= skip."""
    rec = r.run.record
    after = rec.t >= r.skip
    for col, (signal, scale) in enumerate(
        ((rec.tracking_error[after, i], 1e6), (rec.disturbance_error[after, i], 1.0))
    ):
        _, seg = finite_segment(rec.t[after], signal)
        if seg.size < 16:
            continue
        f, amp = amplitude_spectrum(seg, r.run.dt_ns / 1e9)
        x, y = log_envelope(f[1:], amp[1:] * scale)
        keep = (x > 0) & (y > 0)  # an axis held still (braked) has no spectrum to draw
        if keep.any():
            ax_row[col].loglog(x[keep], y[keep], lw=0.6, color=color, label=r.label)


def _style_spectrum(a: Axes, axis: str, what: str, freqs: list[float]) -> None:
    from matplotlib.ticker import LogLocator, NullFormatter

    if not a.lines:
        a.set_xscale('linear')
        a.set_yscale('linear')

    # decades only: minor tick labels on 10 decades cost seconds to lay out
    for axis_ in (a.xaxis, a.yaxis):
        axis_.set_major_locator(LogLocator(numticks=8))
        axis_.set_minor_locator(LogLocator(subs=(2, 5), numticks=8))
        axis_.set_minor_formatter(NullFormatter())
    for fr in freqs:
        a.axvline(fr, color='0.4', ls=':', lw=0.8)
    a.set_title(f'{axis} axis: amplitude spectrum of {what.split(" [")[0]}', loc='left')
    a.set_ylabel(f'amplitude [{what.split("[")[1]}')
    a.set_xlabel('frequency [Hz]')
    if a.lines:
        a.legend(loc='lower left', title=f'dotted: {", ".join(hz(f) for f in freqs)}')


def loop_timing_figure(reports: list[RunReport]) -> Figure:
    """Histogram of the wall-clock sample period as received, runs overlaid."""
    fig, ax = _layout(1, 1, 7, 3.6)
    a = ax[0, 0]
    for c, r in enumerate(reports):
        w = r.run.state_wall_ns
        if w is None:
            continue  # a record without arrival times (the caller passes runs that have them)
        ok = (w[1:] > 0) & (w[:-1] > 0)
        periods = (w[1:] - w[:-1])[ok] / 1e6
        if periods.size:
            top = np.percentile(periods, 99.9)
            bins = np.linspace(0, max(top, 1e-3), 80)
            a.hist(
                np.clip(periods, 0, top), bins=bins, histtype='step', color=f'C{c}', label=r.label
            )
    a.set_yscale('log')
    a.set_xlabel('wall-clock time between consecutive samples [ms] (clipped at p99.9)')
    a.set_ylabel('samples')
    a.set_title('Loop timing: sample period as received by the recorder', loc='left')
    a.legend()
    return fig


def latency_figure(reports: list[RunReport]) -> Figure:
    """Histogram of the state -> command latency of every command, per axis, runs overlaid."""
    axes = reports[0].run.axes
    fig, ax = _layout(1, len(axes), 3.6 * len(axes), 3.4)
    for j, axis in enumerate(axes):
        a = ax[0, j]
        for r in reports:
            lat = r.run.command_latency_ms.get(axis, np.zeros(0))
            lat = lat[np.isfinite(lat)]
            if lat.size:
                a.hist(lat, bins=60, histtype='step', label=r.label)
        a.set_yscale('log')
        a.set_title(f'{axis} axis', loc='left')
        a.set_xlabel('latency: command received − state stamp [ms]')
        if a.patches:
            a.legend()
    return fig


# -- rendering -------------------------------------------------------------------------------


_PLOTS: list[tuple[Plot, Path]] = []


def _render(i: int) -> str | None:
    """Draw one figure; the reason it could not be drawn, if it could not (one line)."""
    job, out = _PLOTS[i]
    try:
        fig = job.make()
        try:
            fig.savefig(out / job.name)
        finally:
            _pyplot().close(fig)
    except (ValueError, OverflowError) as exc:  # data a plot cannot show (all NaN, all <= 0)
        return f'{job.name} not drawn: {exc}'
    return None


def render(jobs: list[Plot], out: Path, workers: int) -> list[tuple[str, str]]:
    """Draw and save the figures, in `workers` forked processes if more than one; a figure
    the data cannot make is left out and said so on stderr."""
    global _PLOTS  # read by the forked workers
    _PLOTS = [(job, out) for job in jobs]
    try:
        if workers > 1 and len(jobs) > 1:
            import multiprocessing

            with multiprocessing.get_context('fork').Pool(workers) as pool:
                problems = pool.map(_render, range(len(jobs)), chunksize=1)
        else:
            problems = [_render(i) for i in range(len(jobs))]
    finally:
        _PLOTS = []
    for problem in problems:
        if problem:
            print(f'report: {problem}', file=sys.stderr)
    return [(job.name, job.caption) for job, p in zip(jobs, problems, strict=True) if not p]


def _nice(x: float) -> float:
    """The largest of 1, 2, 5 x 10^n not above x (at least 1)."""
    if not x > 1:
        return 1.0
    exp = math.floor(math.log10(x))
    for m in (5, 2, 1):
        if m * 10**exp <= x:
            return float(m * 10**exp)
    return float(10**exp)
