"""The numbers of a report: per run and axis metrics, error spectra, windowed RMS, loop timing.

Pure numpy on a BagRun (mill_analysis.bag_run): max |e|, RMS e, the RMS of xi_hat - xi
and of xi and the contour error come from the run's summary (mill_analysis.summary, the
value the runner prints its summary from); the rest is computed here over the summary's
window.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from mill_common.signals import AXES

from mill_analysis.metrics import Contour, ContourMetrics, contour_error, peak, rms
from mill_analysis.summary import AxisFigures, AxisSummary

if TYPE_CHECKING:
    from mill_analysis.bag_run import BagRun


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
    summary: AxisFigures
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
    figures: AxisSummary | None = None  # the run's summary (what the runner prints)
    contour: Contour | None = None  # per sample (the plots)

    @property
    def summary(self) -> list[AxisFigures]:
        return [a.summary for a in self.axes]

    @property
    def contour_summary(self) -> ContourMetrics | None:
        return None if self.figures is None else self.figures.contour


def _finite(x: np.ndarray) -> np.ndarray:
    return x[np.isfinite(x)]


def _stat(fn: Callable[[np.ndarray], Any], x: np.ndarray) -> float:
    x = _finite(x)
    return float(fn(x)) if x.size else math.nan


def analyse(
    run: BagRun, label: str, summary: AxisSummary, window: float, freqs: list[float]
) -> RunReport:
    rec = run.record
    dt_s = run.dt_ns / 1e9
    after = summary.window.mask(rec.t)
    t = rec.t[after]
    e = rec.tracking_error[after]
    d = rec.disturbance_error[after]
    tau = rec['torque'][after]
    force = rec['force'][after]
    width = max(1, round(window / dt_s))
    figures = {m.axis: m for m in summary.axes}
    axes = []
    for axis in run.axes:
        i = AXES.index(axis)
        if axis not in figures:
            continue
        _, ei = finite_segment(t, e[:, i])
        _, di = finite_segment(t, d[:, i])
        axes.append(
            AxisReport(
                axis=axis,
                summary=figures[axis],
                max_window_rms_error=max_window_rms(e[:, i], width),
                max_disturbance_error=peak(d[:, i]),
                error_amplitude={f: amplitude_at(ei, dt_s, f) for f in freqs},
                disturbance_error_amplitude={f: amplitude_at(di, dt_s, f) for f in freqs},
                rms_torque=rms(tau[:, i]),
                max_torque=peak(tau[:, i]),
                force_mean=_stat(np.mean, force[:, i]),
                force_std=_stat(np.std, force[:, i]),
                force_max=peak(force[:, i]),
            )
        )
    report = RunReport(label, run, summary.skip, window, freqs, axes, figures=summary)
    report.loop = loop_timing(run)
    report.contour = contour_error(rec, summary.approach)
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
