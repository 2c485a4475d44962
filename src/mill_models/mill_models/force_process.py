"""Cutting-force process of Rubio 2013 eq. (1)-(3): feed command → peak cutting force (ROS-free).

Readings (papers README, "Rubio 2013"):

- Input: the feed-rate command f_c, the table feed velocity in mm/s (eq. (1) states
  "f_a and f_c are the actual and command velocity values of the table in mm/s"); not the
  feed per tooth. The feed per tooth is f/(N_t·S_s).
- Output: the resultant (peak) cutting force F_p in N.
- eq. (1): CNC feed drive τ_m·ḟ_a = −f_a + f_c. Eq. (1) and eq. (6) write τ_s; section 5
  gives it as τ_m = 0.1 s, the same constant.
- eq. (2): cutting process G_p = K_p/(τ_c s + 1), K_p = K_c·a_dc·r/(N_t·S_s) with
  K_c the cutting pressure [N/mm²], a_dc the axial depth of cut [mm], r the immersion
  function [-], N_t the number of flutes and S_s the spindle speed [rev/s]. K_p is in
  N·s/mm (N per mm/s of feed); the paper's "kN·s/mm" is a misprint.
- τ_c: section 5 prints "τ_c = 1/(N_s S_c)", read as 1/(N_t·S_s), the tooth-passing
  period (0.021 s at 715 rpm with 4 flutes).
- a_dc(t) is piecewise constant in time (section 5: "the cutting process is assumed ...
  piecewise constant, admitting sudden changes"). The realisation puts the depth on the
  output: τ_c·ẋ_c = −x_c + f_a, F_p = K_p(a_dc(t))·x_c. The lagged feed x_c is continuous;
  the force jumps with the depth when the tool meets a step, as a real force does (the
  paper's fig. 4-8 show force peaks at each depth change). With a constant depth this is
  exactly eq. (3).
- Fig. 3 (the workpiece) is not in the text. The default profile, chosen here, has steps
  up and down: 2 mm from 0 s, 3 mm from 2 s, 1.5 mm from 4 s, 3.5 mm from 6 s, 2 mm
  from 8 s. The depth is a function of time, as in the paper (not of tool position).

Integration is exact: between two instants the input is affine, u(τ) = u0 + slope·τ (the
β fractional-order hold reconstructs u_k + β(u_k − u_{k−1})·τ/T within a sample), so the
augmented state [x; u; slope] evolves as ż = M z and z(τ + h) = expm(M h)·z(τ).

Who uses it: the plant simulates the cut with ForceProcessPlant behind the drive's feed
clamp (mill_plant.force_drive, mill_plant.force_process_node); the force controllers design
with ForceProcessModel and run ForceProcessPlant copies as the shadow models of the
multi-model schemes (mill_controllers.model_reference, mill_controllers.multi_model).
"""

from __future__ import annotations

import bisect
import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from mill_common.declared import Configured, ParamSet, param
from mill_common.parameters import (
    ParameterError,
    non_negative,
    positive,
    whole_in,
)

# (start time [s], axial depth of cut [mm]); our reading of Rubio 2013 fig. 3.
DEFAULT_DEPTH_PROFILE: tuple[tuple[float, float], ...] = (
    (0.0, 2.0),
    (2.0, 3.0),
    (4.0, 1.5),
    (6.0, 3.5),
    (8.0, 2.0),
)


def flatten_profile(profile: Sequence[tuple[float, float]]) -> list[float]:
    """[(t0, a0), (t1, a1), ...] → [t0, a0, t1, a1, ...] (the parameter's flat form)."""
    return [float(v) for pair in profile for v in pair]


def _depth_profile_check(value: Any) -> str | None:
    if not isinstance(value, list | tuple) or len(value) < 2 or len(value) % 2:
        return 'must be a flat list [t0, depth0, t1, depth1, ...] of even length >= 2'
    for v in value:
        if not isinstance(v, int | float) or isinstance(v, bool) or not math.isfinite(v):
            return 'must contain finite numbers only'
    times = value[0::2]
    depths = value[1::2]
    if times[0] != 0:
        return 'the first start time must be 0'
    if any(b <= a for a, b in itertools.pairwise(times)):
        return 'start times must be strictly increasing'
    if any(d <= 0 for d in depths):
        return 'depths must be > 0 [mm]'
    return None


def affine_input_exponential(a: np.ndarray, b: np.ndarray, h: float) -> np.ndarray:
    """expm(M·h) for ż = M z, z = [x; u; slope], ẋ = A x + B u, u̇ = slope, (slope)˙ = 0.

    Rows [:n] give x(h) = Φ(h)·x + Γ0(h)·u(0) + Γ1(h)·slope with Φ = E[:n, :n],
    Γ0 = E[:n, n] = ∫0^h e^{Aσ}dσ·B and Γ1 = E[:n, n+1] = ∫0^h e^{A(h−σ)}·σ dσ·B.
    """
    a = np.atleast_2d(np.asarray(a, dtype=float))
    n = a.shape[0]
    m = np.zeros((n + 2, n + 2))
    m[:n, :n] = a
    m[:n, n] = np.asarray(b, dtype=float).reshape(n)
    m[n, n + 1] = 1.0
    import scipy.linalg  # here: the processes that never sample a force loop need not load it

    return scipy.linalg.expm(m * h)


class AffineLti:
    """Exact response of ẋ = A x + B u, y = C x to affine inputs, cached per step length."""

    def __init__(self, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> None:
        self.a = np.atleast_2d(np.asarray(a, dtype=float))
        self.n = self.a.shape[0]
        self.b = np.asarray(b, dtype=float).reshape(self.n)
        self.c = np.asarray(c, dtype=float).reshape(self.n)
        self._cache: dict[float, np.ndarray] = {}

    def exponential(self, h: float) -> np.ndarray:
        key = float(h)
        e = self._cache.get(key)
        if e is None:
            if len(self._cache) > 256:
                self._cache.clear()
            e = affine_input_exponential(self.a, self.b, key)
            self._cache[key] = e
        return e

    def propagate(self, x: np.ndarray, u0: float, slope: float, h: float) -> np.ndarray:
        """State after h [s] from x with input u0 + slope·τ."""
        if h == 0.0:
            return np.array(x, dtype=float)
        e = self.exponential(h)
        n = self.n
        return e[:n, :n] @ x + e[:n, n] * u0 + e[:n, n + 1] * slope

    def grid(
        self, x: np.ndarray, u0: float, slope: float, duration: float, intervals: int
    ) -> np.ndarray:
        """States at τ = j·duration/intervals, j = 0..intervals (rows); exact."""
        h = duration / intervals
        n = self.n
        out = np.empty((intervals + 1, n))
        z = np.concatenate([np.asarray(x, dtype=float), [u0, slope]])
        out[0] = z[:n]
        if intervals and h > 0.0:
            e = self.exponential(h)
            for j in range(1, intervals + 1):
                z = e @ z
                out[j] = z[:n]
        else:
            out[1:] = z[:n]
        return out


@dataclass(frozen=True)
class ForceProcessParams(ParamSet):
    """The process's parameters, Rubio 2013 §5 (and our reading of fig. 3)."""

    PREFIX: ClassVar[str] = 'force_process'
    spindle_speed: float = param(715.0, 'spindle speed S_s [rpm] (Rubio 2013 §5)', positive)
    cutting_pressure: float = param(
        1200.0,
        'specific cutting pressure K_c [N/mm^2] (aluminium, Rubio 2013 §5)',
        positive,
    )
    flutes: int = param(4, 'number of teeth N_t of the cutter', whole_in(1, 100), unit='-')
    immersion: float = param(
        4.0, 'immersion function r(φ_st, φ_ex, N_t) [-] (r = 4, full immersion, §5)', positive
    )
    drive_time_constant: float = param(
        0.1,
        'CNC feed-drive time constant τ_m (printed τ_s in eq. (1), (6))',
        positive,
        unit='s',
    )
    process_time_constant: float = param(
        0.0,
        'cutting-process time constant τ_c [s]; 0 = 1/(N_t·S_s), the tooth period',
        non_negative,
    )
    depth_profile: list[float] = param(
        flatten_profile(DEFAULT_DEPTH_PROFILE),
        'axial depth of cut a_dc(t): flat [t0, a0, t1, a1, ...], start times [s] from 0, '
        'depths [mm] > 0, piecewise constant (our reading of Rubio 2013 fig. 3)',
        _depth_profile_check,
    )


class ForceProcessModel(Configured):
    """Parameters and derived quantities of Rubio 2013 eq. (1)-(3) (no state)."""

    PARAMS: ClassVar[type[ForceProcessParams]] = ForceProcessParams

    def __init__(self, params: ForceProcessParams = ForceProcessParams()) -> None:
        self.spindle_speed_rpm = params.spindle_speed
        self.cutting_pressure = params.cutting_pressure
        self.flutes = params.flutes
        self.immersion = params.immersion
        self.tau_m = params.drive_time_constant
        tau_c = params.process_time_constant
        # Rubio 2013 §5: τ_c = 1/(N_t·S_s) (printed "1/(N_s S_c)")
        self.tau_c = tau_c if tau_c > 0 else 1.0 / (self.flutes * self.spindle_speed_rev_s)
        self._times = [float(t) for t in params.depth_profile[0::2]]
        self._depths = [float(d) for d in params.depth_profile[1::2]]

    @classmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> ForceProcessModel:
        """Build from a mapping keyed by the parameters' names (missing names take defaults)."""
        return cls(cls.PARAMS.from_values(values))

    # --- derived quantities ------------------------------------------------------------

    @property
    def spindle_speed_rev_s(self) -> float:
        """S_s [rev/s]."""
        return self.spindle_speed_rpm / 60.0

    @property
    def sample_period(self) -> float:
        """T = 1/S_s [s], one spindle revolution (Rubio 2013 §5: T = 60/715 s)."""
        return 60.0 / self.spindle_speed_rpm

    @property
    def depth_profile(self) -> tuple[tuple[float, float], ...]:
        return tuple(zip(self._times, self._depths, strict=True))

    def depth_at(self, t: float) -> float:
        """a_dc(t) [mm], right-continuous; the first depth also before t = 0."""
        i = bisect.bisect_right(self._times, t) - 1
        return self._depths[max(i, 0)]

    def depth_changes(self, t0: float, t1: float) -> list[float]:
        """Start times of depth segments strictly inside (t0, t1)."""
        return [t for t in self._times if t0 < t < t1]

    def process_gain(self, depth: float) -> float:
        """K_p = K_c·a_dc·r/(N_t·S_s) [N·s/mm], Rubio 2013 eq. (2)-(3)."""
        # Rubio 2013 eq. (3): K_p = K_c a_dc r_dc / (N_t S_s)
        return (
            self.cutting_pressure
            * depth
            * self.immersion
            / (self.flutes * self.spindle_speed_rev_s)
        )

    def gain_at(self, t: float) -> float:
        return self.process_gain(self.depth_at(t))

    def state_space(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(A, B, C) of the unit-gain plant, state [f_a, x_c] [mm/s]; F_p = K_p·C·x."""
        # Rubio 2013 eq. (1): τ_m ḟ_a = −f_a + f_c;  eq. (2): τ_c ẋ_c = −x_c + f_a
        a = np.array([[-1.0 / self.tau_m, 0.0], [1.0 / self.tau_c, -1.0 / self.tau_c]])
        b = np.array([1.0 / self.tau_m, 0.0])
        c = np.array([0.0, 1.0])
        return a, b, c

    def unit_transfer_function(self) -> tuple[np.ndarray, np.ndarray]:
        """(num, den) of G_c(s)/K_p = 1/((τ_c s + 1)(τ_m s + 1)), highest power first."""
        # Rubio 2013 eq. (3): G_c(s) = K_p / ((τ_c s + 1)(τ_m s + 1))
        den = np.polymul([self.tau_c, 1.0], [self.tau_m, 1.0])
        return np.array([1.0 / den[0]]), den / den[0]

    def steady_feed(self, force: float, depth: float) -> float:
        """Feed [mm/s] that holds `force` [N] at `depth` [mm] in steady state."""
        return force / self.process_gain(depth)


class ForceProcessPlant(Configured):
    """Simulated cutting-force process: integrates eq. (1)-(2) exactly under affine inputs.

    step(u0, slope, duration) applies the feed command u(τ) = u0 + slope·τ [mm/s] for
    τ ∈ [0, duration] and returns the force at the end [N]. trace() does the same and also
    returns the force on a grid, split at the depth changes (each piece is smooth).
    """

    PARAMS: ClassVar[type[ForceProcessParams]] = ForceProcessParams

    def __init__(self, model: ForceProcessModel | None = None) -> None:
        self.model = model or ForceProcessModel()
        a, b, c = self.model.state_space()
        self._lti = AffineLti(a, b, c)
        self._x = np.zeros(2)
        self._t = 0.0

    @classmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> ForceProcessPlant:
        return cls(ForceProcessModel.from_parameters(values))

    # --- state -------------------------------------------------------------------------

    def reset(self, feed: float = 0.0, t: float = 0.0) -> None:
        """Steady state at a constant feed [mm/s] (0 = at rest) at time t [s]."""
        if not math.isfinite(feed) or not math.isfinite(t):
            raise ValueError(f'reset: feed and t must be finite, got {feed!r}, {t!r}')
        self._x = np.array([feed, feed], dtype=float)
        self._t = float(t)

    def set_state(self, state: Sequence[float] | np.ndarray, t: float) -> None:
        """Set [f_a, x_c] [mm/s] at time t [s] (used to synchronise a model copy)."""
        x = np.asarray(state, dtype=float).reshape(2)
        if not np.all(np.isfinite(x)) or not math.isfinite(t):
            raise ValueError(f'set_state: non-finite state {state!r} or time {t!r}')
        self._x = x.copy()
        self._t = float(t)

    @property
    def state(self) -> np.ndarray:
        """[f_a, x_c]: actual feed and lagged feed [mm/s] (a copy)."""
        return self._x.copy()

    @property
    def time(self) -> float:
        return self._t

    @property
    def feed_actual(self) -> float:
        """f_a [mm/s]."""
        return float(self._x[0])

    @property
    def force(self) -> float:
        """F_p(t) [N] at the current time (depth right-continuous)."""
        return self.model.gain_at(self._t) * float(self._x[1])

    # --- integration -------------------------------------------------------------------

    def step(self, u0: float, slope: float, duration: float) -> float:
        """Advance by duration [s] with feed u0 + slope·τ [mm/s]; return the force [N]."""
        self._check(u0, slope, duration)
        self._x = self._lti.propagate(self._x, u0, slope, duration)
        self._t += duration
        return self.force

    def trace(
        self, u0: float, slope: float, duration: float, spacing: float
    ) -> list[tuple[np.ndarray, np.ndarray]]:
        """Advance like step() and return [(times, forces)] per constant-depth piece.

        Each piece has an even number (>= 2) of equal sub-intervals no longer than
        `spacing` [s] (ready for Simpson's rule); at a depth change the left piece ends
        with the old depth's force and the right piece starts with the new one.
        """
        self._check(u0, slope, duration)
        if not spacing > 0:
            raise ValueError(f'trace: spacing must be > 0, got {spacing!r}')
        t0 = self._t
        t_end = t0 + duration
        cuts = [t0, *self.model.depth_changes(t0, t_end), t_end]
        pieces = []
        x = self._x
        for a, b in itertools.pairwise(cuts):
            h = b - a
            if h <= 0.0:
                continue
            intervals = max(2, 2 * math.ceil(h / (2.0 * spacing)))
            u_a = u0 + slope * (a - t0)
            states = self._lti.grid(x, u_a, slope, h, intervals)
            gain = self.model.gain_at(a)
            times = a + np.linspace(0.0, h, intervals + 1)
            pieces.append((times, gain * states[:, 1]))
            x = states[-1]
        self._x = np.array(x, dtype=float)
        self._t = t_end
        return pieces

    @staticmethod
    def _check(u0: float, slope: float, duration: float) -> None:
        if not (math.isfinite(u0) and math.isfinite(slope)):
            raise ValueError(f'feed command must be finite, got u0={u0!r}, slope={slope!r}')
        if not (math.isfinite(duration) and duration >= 0.0):
            raise ParameterError('duration', duration, 'must be finite and >= 0')
