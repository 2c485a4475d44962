"""Feed override: the path's own time advances at `override` times the sample time (ROS-free).

A CNC's feed-override input scales the path speed without changing the path. With the path
p(τ) of any Trajectory and the override o(k) held over sample k:

    τ(k+1) = τ(k) + o(k)·T,
    x_ref(k) = p(τ(k)),  ẋ_ref(k) = o(k)·p'(τ(k)),  ẍ_ref(k) = o(k)²·p''(τ(k))

(o held constant within a sample, so no do/dt term; with a ramp ȯ over the sample, from a
β-hold, ẍ_ref gains ȯ·p'(τ(k)) and τ advances by ȯT²/2 more). o = 1 is the programmed feed, 0
stops on the path. Values outside [minimum, maximum] are clamped and a non-finite value
holds the last accepted override; `accept` says which happened so the node can report it.

The job ends when its path ends, whatever the override: `JobEnd` finds the last sample,
`settle_time` after the first sample whose path time reaches the end of the path (or at
the `duration` cap, if that comes first).

`PeriodicOverridePath` is the lockstep override of a job whose sender acts once per control
period T_c on a faster sample grid T (a force controller acting once per spindle revolution
on a 1 kHz axis job): the override o_j of control instant j (the first sample at or after
j·T_c, stamped by the sender) sets the reference of the samples from that instant up to
the one before the next; with a ramp ȯ (β-hold) the override of the i-th sample after the
instant is o_j + ȯ·i·T, clamped to the range. Each sample is computed once, in order, in the
trajectory node and in the offline simulator alike.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mill_common.timebase import control_instant, job_steps, sample_index

from mill_trajectory.base import Trajectory, TrajectorySample
from mill_trajectory.hold import Holds
from mill_trajectory.override_limit import FollowedOverride, OverrideLimit

_STILL = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Accepted:
    """The override in effect and why it differs from the value offered (None: it does not)."""

    value: float
    problem: str | None = None


class FeedOverride:
    """Clamps offered overrides to a range and holds the last one over a non-finite value."""

    def __init__(self, minimum: float = 0.0, maximum: float = 1.5, initial: float = 1.0) -> None:
        if not (math.isfinite(minimum) and math.isfinite(maximum) and 0.0 <= minimum <= maximum):
            raise ValueError(f'need 0 <= minimum <= maximum, got [{minimum}, {maximum}]')
        self.minimum, self.maximum = float(minimum), float(maximum)
        self.value = min(max(float(initial), self.minimum), self.maximum)

    def accept(self, offered: float) -> Accepted:
        if not math.isfinite(offered):
            return Accepted(self.value, f'non-finite override {offered} ignored, holding')
        clamped = min(max(offered, self.minimum), self.maximum)
        self.value = clamped
        if clamped != offered:
            return Accepted(
                clamped, f'override {offered:g} outside [{self.minimum:g}, {self.maximum:g}]'
            )
        return Accepted(clamped)


@dataclass(frozen=True)
class JobEnd:
    """Where a job with a feed override ends, in samples of period dt_ns."""

    path_end: float  # path time at which the path ends [s]
    settle_samples: int  # samples after the one where the path ends
    cap: int | None  # last sample allowed (the duration), None: no cap

    @classmethod
    def of(cls, path_end: float, settle_time: float, duration: float, dt_ns: int) -> JobEnd:
        """settle_time [s] of machine time after the path ends; duration > 0 caps the job."""
        settle = job_steps(settle_time, dt_ns) - 1  # the first sample at or after settle_time
        cap = job_steps(duration, dt_ns) - 1 if duration > 0 else None
        return cls(path_end, settle, cap)


class TimeScaledPath:
    """A path sampled on its own time τ, which runs at the override's rate.

    On a planned path (a G-code program: `limit`) the override in effect follows the offered
    one within the limit of its rate and change (mill_trajectory.override_limit), so that the
    reference keeps the planner's acceleration and jerk limits; a β-hold slope is then left
    to the follower.
    """

    def __init__(
        self,
        path: Trajectory,
        sample_period: float,
        end: JobEnd | None = None,
        limit: OverrideLimit | None = None,
        holds: Holds | None = None,
    ) -> None:
        self.path = path
        self.followed = None if limit is None else FollowedOverride(limit)
        # Pauses (M0/M1) and the feed hold (mill_trajectory.hold): None, the path runs on.
        self.holds = holds
        self._T = sample_period
        self._k = 0
        self._tau = 0.0
        self._end = end
        self.last_sample: int | None = None  # the job's last sample, once known

    def _find_end(self) -> None:
        end, k = self._end, self._k
        if end is None or self.last_sample is not None:
            return
        if self._tau >= end.path_end:
            last = k + end.settle_samples
            self.last_sample = last if end.cap is None else min(last, end.cap)
        elif end.cap is not None and k >= end.cap:
            self.last_sample = end.cap

    @property
    def sample_period(self) -> float:
        return self._T

    @property
    def path_time(self) -> float:
        return self._tau

    @property
    def sample_index(self) -> int:
        return self._k

    def sample(self, override: float, slope: float = 0.0) -> TrajectorySample:
        """Reference of the current sample k with override o(k); then moves on to k+1.

        slope ȯ [1/s]: the override ramps as o(k) + ȯ·τ over the sample (a β-hold);
        the path time then advances by o·T + ȯ·T²/2 and ẍ_ref gains ȯ·p'.
        """
        holds = self.holds
        if holds is not None:
            held = holds.hold_at(self._tau)
            if held is not None:  # paused: exactly at rest at the pause, the clock runs on
                self._tau = held
                s = self.path.sample(held)
                self._find_end()  # a duration may end the job during a pause
                self._k += 1
                return TrajectorySample(s.position, _STILL, _STILL, s.spindle)
            override = holds.target(override)  # 0 under a feed hold
        s = self.path.sample(self._tau)
        self._find_end()
        self._k += 1
        followed = self.followed
        if followed is not None:
            o, slope = followed.value, followed.rate  # at this sample's instant
            self._tau += followed.step(override, self._T)
        else:
            o = override
            self._tau += o * self._T + 0.5 * slope * self._T * self._T
        v, a = s.velocity, s.acceleration
        return TrajectorySample(
            s.position,
            (o * v[0], o * v[1], o * v[2]),
            (o * o * a[0] + slope * v[0], o * o * a[1] + slope * v[1], o * o * a[2] + slope * v[2]),
            s.spindle,
        )


@dataclass(frozen=True)
class Answer:
    """The reference samples an override sets: samples first, first + 1, ..."""

    first: int
    samples: list[TrajectorySample]
    problem: str | None = None


class PeriodicOverridePath:
    """The lockstep override of a sender acting once per control period (see the module doc)."""

    def __init__(
        self,
        path: Trajectory,
        dt_ns: int,
        control_period: float,
        override: FeedOverride,
        end: JobEnd | None = None,
        limit: OverrideLimit | None = None,
    ) -> None:
        if not control_period >= dt_ns * 1e-9:
            raise ValueError(
                f'control period {control_period!r} s is shorter than the sample period'
            )
        self.scaled = TimeScaledPath(path, dt_ns * 1e-9, end, limit)
        self.dt_ns = dt_ns
        self.period = float(control_period)
        self.override = override

    @property
    def next_sample(self) -> int:
        """The first sample no override has set yet."""
        return self.scaled.sample_index

    def instant(self, j: int) -> int:
        """Sample of control instant j."""
        return control_instant(j, self.period, self.dt_ns)

    def answer(self, k: int, offered: float, slope: float) -> Answer:
        """Reference samples set by the override stamped at sample k (a control instant).

        Samples from the first one not yet set (k itself in lockstep) up to the one before
        the next control instant. A clamped or held override does not ramp.
        """
        accepted = self.override.accept(offered)
        problem = accepted.problem
        if not math.isfinite(slope):
            problem = f'non-finite override slope {slope} ignored'
            slope = 0.0
        if accepted.value != offered:
            slope = 0.0
        first = self.next_sample
        if k != first:
            note = f'override stamped at sample {k}, expected {first}: it sets samples from {first}'
            problem = f'{problem}; {note}' if problem else note
        stop = self.instant(sample_index(max(k, first) * self.dt_ns, self.period) + 1)
        lo, hi = self.override.minimum, self.override.maximum
        samples = []
        T = self.scaled.sample_period
        for i in range(max(stop - first, 1)):
            o = min(hi, max(lo, accepted.value + slope * i * T))
            samples.append(self.scaled.sample(o, slope if lo < o < hi or slope == 0.0 else 0.0))
        return Answer(first, samples, problem)
