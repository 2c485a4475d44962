"""Identify a rigid axis from a record of its position and command (ROS-free).

The model is the rigid axis of Beltrán 2013 eq. (5) with its disturbance written out:

    x'' = b·u(t − d·T) − α·x' − β·sign(x') − γ

b the input gain [m/s² per N·m], α the viscous friction [1/s], β the Coulomb friction and γ
a constant load (a weight on a vertical axis) as accelerations [m/s²], d the delay in samples
between the sample a command answers and the period it acts in. u is held over a period.

Fitting x'' needs a second difference of the position, which multiplies the encoder's
quantization by 1/T² (a 1 µm encoder at 1 kHz: ±2 m/s² per sample). The fit therefore uses
the equation integrated twice over stretches of steady motion ("windows": the sign of x' is
constant and the axis slides, so sign(x') is known and sticking is left out):

    x(t) − x(0) = v0·t + b·U(t) − α·∫₀ᵗ (x − x(0)) − (β·s + γ)·t²/2

with U the double integral of the held, delayed command (exact for a held input) and v0 a
free start velocity per window. It is linear in (b, α, β, γ): least squares after projecting
out each window's own [1, t], for each candidate delay d; the delay is the one with the
smallest residual. The windows of the last quarter of the record are not used for the fit but
to check it (validation: the model predicts their shape from their start alone).

Confidence intervals are the least-squares ones (95 %, residuals taken as independent):
they say how well the data determine a parameter, not how wrong the model may be, which is
what the held-out windows are for.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.signal import savgol_filter

Z95 = 1.959964  # two-sided 95 % quantile of the normal distribution
NAMES = ('b', 'alpha', 'beta', 'gamma')


class IdentificationError(ValueError):
    """The record cannot give a model; str() says why in one line."""


@dataclass(frozen=True)
class FitSettings:
    """How the record is cut into windows and what the fit must reach to be trusted."""

    max_delay: int = 5  # delays tried: 0 … max_delay samples
    min_speed: float = 5e-3  # an axis moves when its smoothed speed exceeds this [m/s]
    trim: float = 0.005  # left out at each end of a stretch of motion [s]
    max_window: float = 0.3  # longer stretches are cut into windows of this length [s]
    min_window: float = 0.05  # shorter ones are not used [s]
    min_windows: int = 8  # needed, each direction at least a quarter of them
    holdout: float = 0.25  # share of the windows (the last ones) kept to check the fit
    max_gain_error: float = 0.02  # the 95 % interval of b must be within ±this × b
    delay_contrast: float = 2.0  # the second-best delay's residual must be this × the best
    max_rejected: float = 0.2  # of the windows may fit far worse than the others
    max_noise: float = 3.0  # the fit's RMS residual may be this × the measurement's noise
    delay: int | None = None  # the delay when known (a two-mass axis's, from its response):
    # only it is fitted, and no other delay is asked to fit worse


@dataclass(frozen=True)
class Window:
    start: int  # first sample
    stop: int  # one past the last
    sign: float  # sign of the velocity in it


@dataclass(frozen=True)
class Interval:
    value: float
    half_width: float  # of the 95 % confidence interval

    def text(self, scale: float = 1.0, digits: int = 4) -> str:
        return f'{self.value * scale:.{digits}g} ± {self.half_width * abs(scale):.2g}'


@dataclass(frozen=True)
class AxisIdentification:
    """The identified model of one axis and how well the record supports it."""

    sample_period: float  # [s]
    delay: int  # [samples]
    b: Interval  # input gain [m/s² per N·m]
    alpha: Interval  # viscous friction [1/s]
    beta: Interval  # Coulomb friction [m/s²]
    gamma: Interval  # constant load, towards −axis [m/s²]
    resolution: float  # smallest position step seen [m]
    windows: int  # used for the fit
    rejected: int  # left out of the fit: they fit far worse than the others
    held_out: int  # used to check it
    fit_rms: float  # residual of the fit [m]
    validation_rms: float  # residual on the held-out windows [m]
    delay_residuals: tuple[float, ...] = field(default=())  # per delay 0 … max_delay [m²]
    noise: float = math.nan  # the measurement's own noise, RMS (noise_floor) [m]

    def torque(self, name: str) -> Interval:
        """A friction or load term as the motor torque that balances it [N·m, N·m·s/m]."""
        term: Interval = getattr(self, name)
        b = self.b
        # both intervals propagated to first order
        half = math.hypot(term.half_width / b.value, term.value * b.half_width / b.value**2)
        return Interval(term.value / b.value, half)

    def as_dict(self) -> dict[str, float | int]:
        out: dict[str, float | int] = {'sample_period': self.sample_period, 'delay': self.delay}
        for name in NAMES:
            iv: Interval = getattr(self, name)
            out[name], out[f'{name}_ci'] = iv.value, iv.half_width
        out.update(
            resolution=self.resolution,
            fit_rms=self.fit_rms,
            validation_rms=self.validation_rms,
            windows=self.windows,
            rejected=self.rejected,
            held_out=self.held_out,
        )
        return out


def motion_windows(x: np.ndarray, T: float, s: FitSettings) -> list[Window]:
    """Stretches of steady-direction sliding, trimmed and cut to at most max_window."""
    n_smooth = max(5, 2 * round(0.005 / T) + 1)  # ±5 ms: the speed, not the encoder's steps
    if len(x) < n_smooth:
        return []
    v = savgol_filter(x, n_smooth, 2, deriv=1, delta=T)
    direction = np.where(np.abs(v) > s.min_speed, np.sign(v), 0.0)
    edges = np.flatnonzero(np.diff(direction)) + 1
    bounds = np.concatenate([[0], edges, [len(x)]])
    trim, longest, shortest = (max(1, round(w / T)) for w in (s.trim, s.max_window, s.min_window))
    out: list[Window] = []
    for a, e in itertools.pairwise(bounds):
        sign = float(direction[a])
        a, e = int(a) + trim, int(e) - trim
        if sign == 0.0:
            continue
        while e - a >= shortest:
            stop = min(e, a + longest)
            if stop - a >= shortest:
                out.append(Window(a, stop, sign))
            a = stop
    return out


def _columns(x: np.ndarray, u: np.ndarray, T: float, w: Window, d: int):
    """The window's columns for (b, α, β, γ), its x − x(0) and its t."""
    k = np.arange(w.start, w.stop)
    ud = u[k - d]
    # A held input u_k over [kT, (k+1)T): V_{k+1} = V_k + T u_k, U_{k+1} = U_k + T V_k + T²/2 u_k
    V = np.concatenate([[0.0], np.cumsum(T * ud)])[:-1]
    U = np.concatenate([[0.0], np.cumsum(T * V + 0.5 * T * T * ud)])[:-1]
    t = (k - w.start) * T
    rel = x[k] - x[w.start]
    X1 = np.concatenate([[0.0], np.cumsum(0.5 * T * (rel[1:] + rel[:-1]))])  # trapezoid
    half_t2 = 0.5 * t * t
    return np.column_stack([U, -X1, -w.sign * half_t2, -half_t2]), rel, t


def _regressors(x: np.ndarray, u: np.ndarray, T: float, w: Window, d: int):
    """The window's columns and target with its own start line [1, t] projected out."""
    cols, rel, t = _columns(x, u, T, w, d)
    q, _ = np.linalg.qr(np.column_stack([np.ones_like(t), t]))
    return cols - q @ (q.T @ cols), rel - q @ (q.T @ rel)


def _stack(x, u, T, windows, d):
    parts = [_regressors(x, u, T, w, d) for w in windows]
    return np.vstack([p[0] for p in parts]), np.concatenate([p[1] for p in parts])


def noise_floor(x: np.ndarray) -> float:
    """The position measurement's own noise, RMS [m]: the encoder's quantization q/√12,
    unless the noise of the third differences is well above it (a smooth motion has hardly
    any: white noise of variance s² gives Δ³ of variance 20·s²; taken robustly, the median
    absolute deviation ×1.4826). Quantization alone is not white when the axis moves slowly,
    which raises the Δ³ estimate somewhat: below twice q/√12 it is not taken."""
    q = resolution_of(x) / math.sqrt(12.0)  # uniform quantization error: q/√12
    d3 = np.diff(np.asarray(x, float), 3)
    if d3.size < 10:
        return q
    spread = 1.4826 * float(np.median(np.abs(d3 - np.median(d3)))) / math.sqrt(20.0)
    return spread if spread > 2.0 * q else q


def resolution_of(x: np.ndarray) -> float:
    steps = np.abs(np.diff(x))
    steps = steps[steps > 1e-12]
    return float(steps.min()) if steps.size else 0.0


def identify_axis(
    x: np.ndarray, u: np.ndarray, T: float, settings: FitSettings | None = None
) -> AxisIdentification:
    """Fit the model to positions x [m] and commands u (u[k] answers x[k]) sampled every T."""
    s = settings or FitSettings()
    x, u = np.asarray(x, float), np.asarray(u, float)
    if x.shape != u.shape or x.ndim != 1:
        raise IdentificationError('positions and commands must be two series of equal length')
    if not (np.isfinite(x).all() and np.isfinite(u).all()):
        raise IdentificationError('the record has missing or non-finite samples')
    fit, held = split_windows(x, T, s)
    if s.delay is not None and not 0 <= s.delay < s.max_delay:
        raise IdentificationError(f'the delay given, {s.delay}, is not within 0-{s.max_delay - 1}')
    results = [_robust_fit(x, u, T, fit, d) for d in range(s.max_delay + 1)]
    rss = [r.rss for r in results]
    d = int(np.argmin(rss)) if s.delay is None else s.delay
    chosen = results[d]
    best, theta, A, n = chosen.rss, chosen.theta, chosen.A, chosen.n
    second = min(r for i, r in enumerate(rss) if i != d) if s.delay is None else math.inf
    if d == s.max_delay:
        raise IdentificationError(
            f'no delay within 0-{s.max_delay} samples fits (the best is the largest tried): '
            f'raise max_delay, or check that the commands recorded are the ones applied'
        )
    if second < s.delay_contrast * best:
        raise IdentificationError(
            f'the delay is ambiguous ({d} and another fit within {s.delay_contrast:g}x): too '
            f'little excitation at high frequency (a shorter bit period)'
        )
    if len(chosen.rejected) > s.max_rejected * len(fit):
        raise IdentificationError(
            f'the rigid model fits only {len(fit) - len(chosen.rejected)} of {len(fit)} '
            f'stretches of motion (the others {OUTLIER:g}x worse than the median): compliance, '
            f'backlash or a position-dependent load that this model does not have'
        )
    fit = [w for i, w in enumerate(fit) if i not in chosen.rejected]
    dof = n - 2 * len(fit) - len(NAMES)
    cov = (best / dof) * np.linalg.inv(A.T @ A)
    half = Z95 * np.sqrt(np.diag(cov))
    b, alpha, beta, gamma = (Interval(float(v), float(h)) for v, h in zip(theta, half, strict=True))
    ident = AxisIdentification(
        T,
        d,
        b,
        alpha,
        beta,
        gamma,
        resolution=resolution_of(x),
        windows=len(fit),
        rejected=len(chosen.rejected),
        held_out=len(held),
        fit_rms=math.sqrt(best / n),
        validation_rms=_validation_rms(x, u, T, fit, held, d, theta),
        delay_residuals=tuple(rss),
        noise=noise_floor(x),
    )
    check_consistent(ident, s)
    return ident


OUTLIER = 5.0  # a window whose residual is this many times the median one is left out


@dataclass
class _Fit:
    rss: float
    theta: np.ndarray
    A: np.ndarray
    n: int
    rejected: set[int]  # indices of the windows left out


def _window_rms(A: np.ndarray, y: np.ndarray, theta: np.ndarray, sizes: list[int]) -> np.ndarray:
    r2 = (y - A @ theta) ** 2
    ends = np.cumsum(sizes)
    return np.sqrt(np.add.reduceat(r2, ends - np.asarray(sizes)) / np.asarray(sizes))


def _robust_fit(x: np.ndarray, u: np.ndarray, T: float, windows: list[Window], d: int) -> _Fit:
    """Least squares over the windows; then once more without the windows that fit far
    worse than the median (a stick the smoothed speed hid, a bump in the guideway)."""
    sizes = [w.stop - w.start for w in windows]
    A, y = _stack(x, u, T, windows, d)
    theta, *_ = np.linalg.lstsq(A, y, rcond=None)
    per = _window_rms(A, y, theta, sizes)
    rejected = {int(i) for i in np.flatnonzero(per > OUTLIER * np.median(per))}
    if rejected:
        kept = [w for i, w in enumerate(windows) if i not in rejected]
        A, y = _stack(x, u, T, kept, d)
        theta, *_ = np.linalg.lstsq(A, y, rcond=None)
    r = y - A @ theta
    return _Fit(float(r @ r), theta, A, len(y), rejected)


def split_windows(x: np.ndarray, T: float, s: FitSettings) -> tuple[list[Window], list[Window]]:
    """The windows to fit and, after them in time, the ones held out to check the fit."""
    windows = [w for w in motion_windows(x, T, s) if w.start >= s.max_delay]
    each = [sum(w.sign == sg for w in windows) for sg in (1.0, -1.0)]
    if len(windows) < s.min_windows or min(each) < s.min_windows // 4:
        raise IdentificationError(
            f'too little motion to identify: {each[0]} stretch(es) of steady motion in +, '
            f'{each[1]} in - above {1e3 * s.min_speed:g} mm/s (need {s.min_windows}, a quarter '
            f'in each direction): more excitation, or a longer record'
        )
    n_fit = max(s.min_windows, round(len(windows) * (1.0 - s.holdout)))
    return windows[:n_fit], windows[n_fit:]


def held_out_windows(m: AxisIdentification, x: np.ndarray, s: FitSettings) -> list[Window]:
    return split_windows(np.asarray(x, float), m.sample_period, s)[1]


def _validation_rms(x, u, T, fit, held, d, theta) -> float:
    """RMS residual on the held-out windows, leaving out those that fit as badly as the
    windows the fit left out (OUTLIER times the fit windows' median)."""
    if not held:
        return math.nan
    fit_sizes, sizes = [w.stop - w.start for w in fit], [w.stop - w.start for w in held]
    A_fit, y_fit = _stack(x, u, T, fit, d)
    typical = np.median(_window_rms(A_fit, y_fit, theta, fit_sizes))
    A, y = _stack(x, u, T, held, d)
    per = _window_rms(A, y, theta, sizes)
    keep = per <= OUTLIER * typical
    if not keep.any():
        return float(np.sqrt(np.mean(per**2)))
    return float(
        np.sqrt(np.sum(per[keep] ** 2 * np.asarray(sizes)[keep]) / np.sum(np.asarray(sizes)[keep]))
    )


def check_consistent(m: AxisIdentification, s: FitSettings) -> None:
    """IdentificationError if the model is unstable, unphysical or not supported by the data."""
    b = m.b
    if b.value <= 0.0:
        raise IdentificationError(
            f'input gain b = {b.value:.4g} m/s² per N·m: the axis accelerates against its '
            f'command (a sign error in the drive, the encoder or the axis direction?)'
        )
    if b.half_width > s.max_gain_error * b.value:
        raise IdentificationError(
            f'too little excitation: b = {b.text()} m/s² per N·m, an interval wider than '
            f'±{100 * s.max_gain_error:g} %: a larger excitation.acceleration or a longer run'
        )
    if math.isfinite(m.noise) and m.fit_rms > s.max_noise * m.noise:
        # A rigid axis leaves only the encoder's noise (docs/bring-up.md: 0.285 µm for a 1 µm
        # encoder); far more is an effect the model does not have, whatever it predicts.
        raise IdentificationError(
            f'the rigid model leaves {1e6 * m.fit_rms:.3g} µm RMS, {m.fit_rms / m.noise:.3g}x '
            f"the measurement's noise ({1e6 * m.noise:.2g} µm): an effect it does not have "
            f'(compliance, backlash, a position-dependent load)'
        )
    if m.alpha.value + m.alpha.half_width < 0.0:
        # Negative beyond its interval. (A negative value within its interval, on a fit down
        # to the noise, is zero damping measured; on a worse fit the check above refused it:
        # issue 32's compliant axis gave −16.8 N·s/m with an interval reaching past zero.)
        raise IdentificationError(
            f'viscous friction α = {m.alpha.text()} 1/s is negative: an unstable model, '
            f'which no rigid axis is (something else drives this axis)'
        )
    if m.beta.value + m.beta.half_width < 0.0:
        raise IdentificationError(
            f'Coulomb friction β = {m.beta.text()} m/s² is negative: the record is not of a '
            f'rigid axis with friction'
        )
    floor = max(3.0 * m.fit_rms, 3.0 * m.resolution)
    if m.validation_rms > floor:
        raise IdentificationError(
            f'the model does not predict the held-out motion: {1e6 * m.validation_rms:.3g} µm '
            f'RMS against {1e6 * m.fit_rms:.3g} µm in the fit (compliance, backlash or a '
            f'position-dependent load that this rigid model does not have)'
        )


def predict_window(
    m: AxisIdentification, x: np.ndarray, u: np.ndarray, w: Window
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """t, measured and predicted x − x(0) over a window (start position and speed fitted)."""
    cols, rel, t = _columns(x, u, m.sample_period, w, m.delay)
    shape = cols @ np.array([m.b.value, m.alpha.value, m.beta.value, m.gamma.value])
    line = np.column_stack([np.ones_like(t), t])
    coef, *_ = np.linalg.lstsq(line, rel - shape, rcond=None)
    return t, rel, shape + line @ coef
