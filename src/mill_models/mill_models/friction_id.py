"""Static (breakaway) and Stribeck friction of an axis from its record (ROS-free).

The rigid fit (mill_models.identification) uses only steady sliding, above a few mm/s, where
friction is its sliding level β (Coulomb) plus α·x' (viscous). What happens below, where the
axis stops, sticks and breaks away again, is friction's low-speed part, the Stribeck curve

    F(v) = sign(v)·(Fc + (Fs − Fc)·exp(−(v/vs)²)) + σ·v

(Olsson, Åström, Canudas de Wit, Gäfvert, Lischinsky 1998, "Friction models and friction
compensation", §2 static models, with the Gaussian exponent δ = 2; all as accelerations, so
Fc = β and σ = α of the rigid fit), with sticking: an axis at rest stays there while the
force on it is within ±Fs.

How: the record's stops (the encoder still for a while) are the stretches where the axis
passes through low speed and the breakaway force decides what it does. Each stop, from a
little before it to a while after it, is simulated from the measured position and speed at
its start with the rigid fit's b, delay, Fc, σ and load and the measured commands, for a
grid of (Fs, vs); the pair whose simulated positions match the measured ones best is the
estimate (least squares; a free offset per stop takes the encoder's quantization of the
start). The interval is the set of grid values whose residual is within the 95 % profile
bound (Δ(residual) ≤ 3.84·σ², σ² the best fit's residual variance). "No Stribeck effect"
when the interval of Fs reaches down to Fc's.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from mill_models.identification import AxisIdentification, Interval

CHI2_95_1 = 3.841459  # 95 % quantile of χ² with one degree of freedom


@dataclass(frozen=True)
class FrictionSettings:
    min_stop: float = 0.006  # the encoder still this long is a stop [s]
    after: float = 0.03  # and after it [s]
    longest: float = 0.04  # of a stop, the last this long is simulated [s]
    max_stops: int = 80  # used (evenly spread over the record)
    resamples: int = 200  # bootstrap of the stops, for the intervals
    min_stops: int = 5  # needed for an estimate
    sub: int = 10  # integration steps per sample
    static_ratios: tuple[float, ...] = tuple(np.round(np.arange(1.0, 3.01, 0.05), 3))
    speeds: tuple[float, ...] = tuple(np.geomspace(2e-4, 2e-2, 17))  # vs tried [m/s]


@dataclass(frozen=True)
class StribeckFriction:
    """Friction against speed, as accelerations (divide by b for the motor torque)."""

    coulomb: Interval  # Fc, the sliding level [m/s²] (the rigid fit's β)
    static: Interval  # Fs, breakaway [m/s²]
    speed: Interval | None  # vs [m/s]; None when there is no Stribeck effect
    viscous: Interval  # σ [1/s] (the rigid fit's α)
    stops: int  # used
    present: bool  # Fs above Fc beyond their intervals
    reason: str  # one line

    def force(self, v: np.ndarray) -> np.ndarray:
        """F(v) for v ≠ 0 [m/s²]."""
        v = np.asarray(v, float)
        return _curve(v, self.coulomb.value, self.static.value, self._vs(), self.viscous.value)

    def _vs(self) -> float:
        return self.speed.value if self.speed is not None else 1e-9

    def as_dict(self) -> dict[str, float | int | bool | str]:
        out: dict[str, float | int | bool | str] = {
            'coulomb': self.coulomb.value,
            'coulomb_ci': self.coulomb.half_width,
            'static': self.static.value,
            'static_ci': self.static.half_width,
        }
        if self.speed is not None:
            out.update(stribeck_speed=self.speed.value, stribeck_speed_ci=self.speed.half_width)
        out.update(stops=self.stops, present=self.present, reason=self.reason)
        return out


def _curve(v: np.ndarray, fc: float, fs: float | np.ndarray, vs: float, sigma: float) -> np.ndarray:
    # Stribeck curve, Olsson et al. 1998 §2 (δ = 2): F = Fc + (Fs − Fc)·e^(−(v/vs)²) + σ·v
    return np.sign(v) * (fc + (fs - fc) * np.exp(-((v / vs) ** 2))) + sigma * v


def stops(x: np.ndarray, T: float, s: FrictionSettings) -> list[tuple[int, int]]:
    """Runs [start, stop) of equal positions at least min_stop long."""
    changes = np.flatnonzero(np.diff(x) != 0.0) + 1
    bounds = np.concatenate([[0], changes, [len(x)]])
    shortest = max(2, round(s.min_stop / T))
    return [(int(a), int(e)) for a, e in itertools.pairwise(bounds) if e - a >= shortest]


def estimate_friction(
    x: np.ndarray,
    u: np.ndarray,
    m: AxisIdentification,
    settings: FrictionSettings | None = None,
) -> StribeckFriction:
    """Fs and vs from the record's stops, given the rigid fit m of the same record."""
    s = settings or FrictionSettings()
    x, u = np.asarray(x, float), np.asarray(u, float)
    T, d = m.sample_period, m.delay
    post = round(s.after / T)
    found = [(a, e) for a, e in stops(x, T, s) if a >= max(d, 1) and e + post <= len(x)]
    fc, sigma = m.beta, m.alpha
    if len(found) < s.min_stops:
        return StribeckFriction(
            fc,
            fc,
            None,
            sigma,
            len(found),
            False,
            f'the axis stopped {len(found)} times (need {s.min_stops}): static friction not '
            f'seen, no Stribeck effect shows',
        )
    if len(found) > s.max_stops:
        pick = np.linspace(0, len(found) - 1, s.max_stops).round().astype(int)
        found = [found[i] for i in pick]
    longest = round(s.longest / T)
    # from the middle of the stop (at rest: the encoder still for half its run on either
    # side) or its last `longest`, to `after` past it
    segments = [(max((a + e) // 2, e - longest), e + post) for a, e in found]
    length = max(e - a for a, e in segments)
    n_seg = len(segments)
    meas = np.full((n_seg, length), np.nan)
    acc = np.zeros((n_seg, length))
    b, gamma = m.b.value, m.gamma.value
    for i, (a, e) in enumerate(segments):
        meas[i, : e - a] = x[a:e] - x[a]
        acc[i, : e - a] = b * u[a - d : e - d] - gamma
    valid = np.isfinite(meas)
    ratios = np.asarray(s.static_ratios)
    speeds = np.asarray(s.speeds)
    # per (Fs, vs, stop): the residual sum of squares
    cost = np.stack(
        [
            _costs(meas, valid, acc, T, s.sub, fc.value, ratios * fc.value, vs, sigma.value)
            for vs in speeds
        ],
        axis=1,
    )
    total = cost.sum(axis=2)
    i_best, j_best = (int(i) for i in np.unravel_index(int(np.argmin(total)), total.shape))
    # the stops resampled (bootstrap): how far the best grid point moves
    rng = np.random.default_rng(0)
    picks = rng.integers(0, n_seg, size=(s.resamples, n_seg))
    boot = np.array(
        [np.unravel_index(int(np.argmin(cost[:, :, p].sum(axis=2))), total.shape) for p in picks]
    )
    fs_grid = ratios * fc.value
    static = _interval(fs_grid, i_best, boot[:, 0])
    # no Stribeck effect when Fs = Fc (the first row) is inside the interval, or fits as well
    if static.value - static.half_width <= fc.value + fc.half_width:
        return StribeckFriction(
            fc,
            static,
            None,
            sigma,
            n_seg,
            False,
            f'no Stribeck effect: breakaway {static.text()} m/s² is the sliding level '
            f'{fc.text()} within its interval ({n_seg} stops)',
        )
    speed = _interval(speeds, j_best, boot[:, 1])
    return StribeckFriction(
        fc,
        static,
        speed,
        sigma,
        n_seg,
        True,
        f'static friction {static.value / fc.value:.2g}x the sliding level, falling with a '
        f'Stribeck speed of {1e3 * speed.value:.2g} mm/s ({n_seg} stops)',
    )


def _interval(grid: np.ndarray, best: int, resampled: np.ndarray) -> Interval:
    """The best grid value, with the half-width that covers 95 % of the resampled best
    values, and at least half the grid's step there (its resolution)."""
    lo, hi = np.quantile(grid[resampled], [0.025, 0.975])
    value = float(grid[best])
    step = 0.5 * float(np.max(np.abs(np.diff(grid[max(0, best - 1) : best + 2]))))
    return Interval(value, max(step, value - float(lo), float(hi) - value))


def _costs(
    meas: np.ndarray,
    valid: np.ndarray,
    acc: np.ndarray,
    T: float,
    sub: int,
    fc: float,
    fs: np.ndarray,
    vs: float,
    sigma: float,
) -> np.ndarray:
    """Residual sum of squares of each stop (columns) simulated from rest with each Fs
    (rows) at one vs."""
    n_seg, length = meas.shape
    shape = (len(fs), n_seg)
    fs_col = fs[:, None]
    x = np.zeros(shape)
    v = np.zeros(shape)
    h = T / sub
    sim = np.empty((len(fs), n_seg, length))
    for k in range(length):
        sim[:, :, k] = x
        a_app = acc[:, k]
        for _ in range(sub):
            moving = v != 0.0
            stuck = ~moving & (np.abs(a_app) <= fs_col)
            # sliding: Stribeck curve; starting: the direction of the force, at Fs
            friction = np.where(
                moving,
                _curve(v, fc, fs_col, vs, sigma),
                np.sign(a_app) * fs_col,
            )
            v_new = np.where(stuck, 0.0, v + h * (a_app - friction))
            v_new = np.where(moving & (v_new * v < 0.0), 0.0, v_new)  # stops at a reversal
            x = x + 0.5 * h * (v + v_new)
            v = v_new
    r = np.where(valid, meas - sim, 0.0)
    offset = r.sum(axis=2) / valid.sum(axis=1)
    r = np.where(valid, r - offset[:, :, None], 0.0)
    return np.asarray((r**2).sum(axis=2))
