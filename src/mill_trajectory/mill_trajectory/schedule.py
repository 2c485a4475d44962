"""Which reference points the trajectory sends, and when. ROS-free.

The trajectory node publishes points of its sample grid ahead of the controllers; the
objects here decide which, from the job's path, and the node only turns them into
messages. The offline simulator asks the same objects, so the controllers of a distributed
run and of the offline one see the same points:

- `ClockedReference` (lockstep): each /clock tick of stamp ns is answered with the samples
  ns, ns + T, … for `preview` samples; with a feed override (`TimeScaledPath`) each sample is
  computed once, in order, with the override in effect when its tick arrives.
- `OverrideReference` (lockstep, a force controller's override paces the job): an override
  stamped at sample k sets the samples from k on — one sample (the force job), or up to the
  next control instant of a slower sender (`PeriodicOverridePath`, the adaptive-feed job).
- `WallClockReference` (realtime): before the job, the points hold the axes where they stand
  on the grid of the newest state's stamp; from the start t0 on, the points of the grid
  t0 + kT from one sample before now to `preview` ahead; the job's path begins with the move
  from where the axes stood (mill_trajectory.approach).
- `JobProgress`: when the job is done (its end time, or with a feed override the sample
  where its path ended) and when to say how far it is.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from mill_common.timebase import sample_stamp_ns, seconds

from mill_trajectory.approach import Approach
from mill_trajectory.base import Trajectory, TrajectorySample
from mill_trajectory.feed_override import FeedOverride, PeriodicOverridePath, TimeScaledPath

OVERRIDE_STAMP_TOLERANCE_NS = 1000


@dataclass(frozen=True)
class Points:
    """Reference samples at stamp_ns, stamp_ns + period_ns, … (one message)."""

    stamp_ns: int
    period_ns: int
    samples: list[TrajectorySample]
    problem: str | None = None  # an override that was clamped, held or late

    def stamps(self) -> list[int]:
        return [self.stamp_ns + i * self.period_ns for i in range(len(self.samples))]


class ClockedReference:
    def __init__(
        self,
        path: Trajectory,
        dt_ns: int,
        preview: int,
        scaled: TimeScaledPath | None = None,
        override: FeedOverride | None = None,
    ) -> None:
        self.path, self.dt_ns, self.preview = path, dt_ns, preview
        self.scaled, self.override = scaled, override

    def answer(self, ns: int) -> Points | None:
        """The points that answer the tick of stamp ns (None: all sent already)."""
        dt = self.dt_ns
        if self.scaled is None:
            samples = [self.path.sample(seconds(ns + i * dt)) for i in range(self.preview)]
            return Points(ns, dt, samples)
        # Each sample once and in order: its path time depends on all earlier overrides.
        first = max(ns // dt, self.scaled.sample_index)
        last = ns // dt + self.preview
        if first >= last:
            return None
        value = 1.0 if self.override is None else self.override.value
        return Points(first * dt, dt, [self.scaled.sample(value) for _ in range(first, last)])

    def job_time(self, ns: int) -> float:
        """Where the job is at the tick ns: the path time under an override."""
        return seconds(ns) if self.scaled is None else self.scaled.path_time


class OverrideReference:
    """Lockstep answers to the overrides that pace the job (see the module doc)."""

    def __init__(
        self,
        scaled: TimeScaledPath,
        override: FeedOverride,
        sample_period: float,
        periodic: PeriodicOverridePath | None = None,
    ) -> None:
        self.scaled, self.override, self.periodic = scaled, override, periodic
        self.sample_period = sample_period
        self.job_time = 0.0  # the path time the last answer reports

    def problem(self, ns: int, newest: int | None) -> str | None:
        """Why an override stamped ns asks for no sample this node can answer."""
        if self.periodic is not None:
            dt = self.periodic.dt_ns
            if ns % dt or (newest is not None and ns < newest):
                what = 'not a sample' if ns % dt else 'in the past'
                return f'stamp {ns / 1e9:.9f} s is {what}'
            return None
        # Each override asks for the next sample. The sender's T may differ from ours in the
        # last digits (the force job allows 1e-12 T): 1 µs is far more than that makes over
        # any job and far less than a period.
        want = sample_stamp_ns(self.scaled.sample_index, self.sample_period)
        if abs(ns - want) > OVERRIDE_STAMP_TOLERANCE_NS:
            what = 'in the past' if ns < want else 'not the next sample'
            return f'stamp {ns / 1e9:.9f} s is {what} (t_k = {want / 1e9:.9f} s)'
        return None

    def answer(self, ns: int, offered: float, slope: float) -> Points:
        """The samples an override stamped ns (checked by `problem`) sets."""
        if self.periodic is not None:
            dt = self.periodic.dt_ns
            got = self.periodic.answer(ns // dt, offered, slope)
            self.job_time = self.scaled.path_time  # where the samples set end
            return Points(got.first * dt, dt, got.samples, got.problem)
        self.job_time = self.scaled.path_time  # the sample answered: where it starts
        accepted = self.override.accept(offered)
        problem = accepted.problem
        if not math.isfinite(slope):
            problem, slope = f'non-finite override slope {slope} ignored', 0.0
        if accepted.value != offered:
            slope = 0.0  # a clamped or held override does not ramp
        return Points(ns, 0, [self.scaled.sample(accepted.value, slope)], problem)


class WallClockReference:
    """Realtime: the hold before the job, then the job on the grid t0 + kT."""

    def __init__(self, path: Trajectory, dt_ns: int, count: int) -> None:
        self.path, self.dt_ns, self.count = path, dt_ns, count
        self.hold_ns: int | None = None  # grid of the hold: the newest state's stamp
        self.t0: int | None = None  # the job's start on the system clock [ns]
        self.approach: Approach | None = None

    def hold(
        self,
        positions: Sequence[float],
        axes: Sequence[int],
        newest_state_ns: int,
        speed: float,
        max_distance: float,
    ) -> Approach:
        """Hold the axes where they stand; ApproachError if they stand too far away."""
        self.approach = Approach(self.path, positions, speed, max_distance, axes)
        self.path = self.approach
        self.hold_ns = newest_state_ns
        return self.approach

    def _k(self, now_ns: int, origin: int) -> int:
        return (now_ns - origin) // self.dt_ns

    def holding(self, now_ns: int) -> Points:
        """Where the axes stand (the approach's first point), on the states' grid."""
        assert self.hold_ns is not None, 'hold() first'
        here = self.path.sample(0.0)
        first = max(0, self._k(now_ns, self.hold_ns) - 1)
        return Points(self.hold_ns + first * self.dt_ns, self.dt_ns, [here] * self.count)

    def start(self, now_ns: int) -> int:
        """Start the job at the hold's grid point of now: its first points replace the held
        ones stamp for stamp. Returns t0."""
        assert self.hold_ns is not None, 'hold() first'
        self.t0 = self.hold_ns + max(self._k(now_ns, self.hold_ns), 0) * self.dt_ns
        return self.t0

    def running(self, now_ns: int) -> Points:
        """The job's points from one sample before now on."""
        assert self.t0 is not None, 'start() first'
        first = max(0, self._k(now_ns, self.t0) - 1)
        dt = self.dt_ns
        samples = [self.path.sample(seconds((first + i) * dt)) for i in range(self.count)]
        return Points(self.t0 + first * dt, dt, samples)


class JobProgress:
    """When the job is done, and when its progress is worth a report (once a second)."""

    def __init__(
        self, end_time: float, scaled: TimeScaledPath | None = None, dt_ns: int = 0
    ) -> None:
        self.end_time = end_time
        # A job with a feed override ends where its path ends, at a sample of period dt_ns.
        self.scaled, self.dt_ns = scaled, dt_ns
        self.done_at: float | None = None  # the job's end, once done
        self._next_report = 0.0

    def update(self, t: float) -> str | None:
        """At job time t: 'done' when the job has just ended, 'running' (or 'done' again)
        when a report is due, else None."""
        done, end = t >= self.end_time, self.end_time
        scaled = self.scaled
        if scaled is not None:
            last = scaled.last_sample
            done = last is not None and scaled.sample_index > last
            if last is not None and done:
                end = seconds(last * self.dt_ns)
        if done and self.done_at is None:
            self.done_at = end
            self._next_report = t + 1.0
            return 'done'
        if t >= self._next_report:
            self._next_report = t + 1.0
            return 'done' if self.done_at is not None else 'running'
        return None

    def restart_reports(self) -> None:
        """The next update reports (the job time starts anew)."""
        self._next_report = 0.0
