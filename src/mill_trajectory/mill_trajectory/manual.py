"""Manual commands between jobs: jog, go home, set home, one G-code line (MDI). ROS-free.

On the wall clock (timing realtime) the trajectory node goes on publishing once its job has
ended: the reference holds the job's last point at rest. While nothing else moves, an
operator may then move the machine by hand:

- **jog** an axis by an increment (a signed distance, at `jog.speed`), or continuously at a
  signed velocity toward the end of its travel until `jog_stop`;
- **home**: a rapid to the home position (the G28 position, gcode.home, until set_home);
- **set_home**: where the reference stands becomes home (as LinuxCNC's G28.1);
- **MDI**: one G-code line, read by mill_trajectory.gcode from where the reference stands
  (the program defaults: G21 G90 G54, no feed; the modal state is not kept from one line to
  the next) and planned by mill_trajectory.planner;
- **jog_stop**: any of these moves decelerates along its path to rest.

Every move is a rest-to-rest path planned within the machine's per-axis velocity,
acceleration and jerk limits (gcode.max_*) and checked against the travel before anything
moves. It runs on its own time like a feed-override job (mill_trajectory.feed_override):
planned with three quarters of the acceleration and jerk left for the override to change
(RESERVE), so that a stop is the feed hold of mill_trajectory.hold, within the limits, along
the path, and quick. A move starts at the first sample after the command; the points
already sent from there on (the hold, at rest) are replaced stamp for stamp, as at the start
of the job.

A command that cannot run is refused with one line saying why (`Order`): a job running or
not started yet, a move under way, timing lockstep (a replay on the plant's clock), an
unknown axis, a target beyond the travel (naming the limit), a speed above the axis limit,
an MDI line that does not read ('mdi:1:column: what').
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

from mill_trajectory.base import Trajectory, TrajectorySample
from mill_trajectory.feed_override import TimeScaledPath
from mill_trajectory.feed_report import pieces_by_block
from mill_trajectory.gcode import Setup, parse_program
from mill_trajectory.gcode_words import GcodeError, Move
from mill_trajectory.hold import Command, Holds
from mill_trajectory.override_limit import OverrideLimit
from mill_trajectory.planner import Limits, Piece, PlanError, PlannedPath, Point, plan
from mill_trajectory.toolpath import Travel, check_travel

AXIS_NAMES = ('x', 'y', 'z')
MDI_FILE = 'mdi'  # the file name an MDI line's problems are reported in ('mdi:1:column')
# The share of the acceleration and jerk limits a manual move leaves for its stop (the feed
# hold's room, mill_trajectory.override_limit): a move accelerates at a quarter of the limits,
# and a stop from 50 mm/s takes 0.22 s and 5.4 mm (0.95 s and 23.7 mm with the 25 % a
# program leaves).
RESERVE = 0.75
_STILL: Point = (0.0, 0.0, 0.0)
_KEEP = 4096  # samples a move keeps computed (the node asks from one before now on)


@dataclass(frozen=True)
class Machine:
    """What manual moves are planned within."""

    limits: Limits  # the machine's per-axis limits (gcode.max_*) and path tolerance
    travel: Travel
    sample_period: float  # [s]
    jog_speed: float  # speed of a jog by increment [m/s]
    setup: Setup  # work offsets, G28/G30 positions, tools: what an MDI line reads with
    work_offset: Point = (0.0, 0.0, 0.0)  # G54


@dataclass(frozen=True)
class Order:
    """The answer to a manual command: taken or not, and one line on it."""

    accepted: bool
    message: str


class Motion(Trajectory):
    """A manual move on the sample grid (t = 0 its first sample): a planned path run on its
    own time, so that `stop` brings it to rest along the path within the limits."""

    def __init__(
        self,
        planned: PlannedPath,
        limit: OverrideLimit | None,
        sample_period: float,
        what: str,
        spindle: float | None,
    ) -> None:
        self.planned, self.what, self.spindle = planned, what, spindle
        self.holds = Holds((), sample_period)
        self.scaled = TimeScaledPath(planned, sample_period, limit=limit, holds=self.holds)
        self._T = sample_period
        self._samples: dict[int, TrajectorySample] = {}
        self.rest_index: int | None = None  # the first sample at rest for good
        self.end_time = math.inf  # unknown until it has come to rest

    def stop(self) -> Command:
        if self.rest_index is not None:
            return Command(False, f'{self.what} has come to rest already')
        if self.holds.held:
            return Command(False, f'{self.what} is stopping already')
        self.holds.feed_hold()
        return Command(True, f'{self.what}: stopping along its path within the limits')

    def at_rest(self, t: float) -> bool:
        """At rest for good from time t on."""
        return self.rest_index is not None and self._index(t) >= self.rest_index

    def _index(self, t: float) -> int:
        return round(t / self._T)

    def _still(self) -> bool:
        scaled = self.scaled
        if scaled.path_time >= self.planned.end_time:
            return True
        followed = scaled.followed
        o = 1.0 if followed is None else followed.value
        return self.holds.held and o <= 0.0

    def sample(self, t: float) -> TrajectorySample:
        k = max(0, self._index(t))
        samples, scaled = self._samples, self.scaled
        while scaled.sample_index <= k:
            j = scaled.sample_index
            s = replace(scaled.sample(1.0), spindle=self.spindle)
            if self.rest_index is None and self._still() and s.velocity == _STILL:
                self.rest_index = j
                self.end_time = j * self._T
            samples[j] = s
            if len(samples) > _KEEP:
                del samples[next(iter(samples))]
        first = next(iter(samples))
        return samples[max(k, first)]


class Spliced(Trajectory):
    """At rest at `rest` before `start` [s], then `motion` from there (its t = 0)."""

    def __init__(self, rest: TrajectorySample, motion: Motion, start: float) -> None:
        self.rest, self.motion, self.start = rest, motion, start

    @property
    def end_time(self) -> float:  # type: ignore[override]
        return self.start + self.motion.end_time

    def sample(self, t: float) -> TrajectorySample:
        return self.rest if t < self.start else self.motion.sample(t - self.start)


def _mm(p: Sequence[float]) -> str:
    return '(' + ', '.join(f'{1e3 * v:.3f}' for v in p) + ') mm'


class Manual:
    """The manual commands of one trajectory node (see the module doc).

    Times t are the job's time [s] (None: the job has not started); the node sets the job's
    path and end once it has started (`job_started`), and publishes `path` from then on.
    """

    def __init__(self, machine: Machine, realtime: bool) -> None:
        self.machine, self.realtime = machine, realtime
        self.home: Point = machine.setup.home
        self.path: Trajectory | None = None  # what the node publishes: the job, then moves
        self.job_end = math.inf  # the job's end [s]
        self.motion: Motion | None = None  # the last manual move
        self._start = 0.0  # its start [s]

    def job_started(self, path: Trajectory, end: float) -> None:
        self.path, self.job_end = path, end

    # -- when a command may run ----------------------------------------------------------
    def busy(self, t: float | None) -> str | None:
        """Why nothing may move by hand at time t (None: it may)."""
        if not self.realtime:
            return (
                "timing lockstep replays a job on the plant's clock, sample by sample: "
                'manual commands need timing realtime'
            )
        if t is None or self.path is None:
            return (
                'the job has not started yet (it starts once every axis controller commands): '
                'wait for it to end'
            )
        motion = self.motion
        if motion is None:
            if t < self.job_end:
                return f'a job is running (t = {t:.2f} s of {self.job_end:.2f} s): wait for its end'
            rest = self.path.end_time + self.machine.sample_period
            if not t >= rest:
                when = f'at t = {rest:.2f} s' if math.isfinite(rest) else 'never'
                return f"the job's path is still moving (it comes to rest {when})"
            return None
        if not motion.at_rest(t - self._start):
            return f'{motion.what} is under way: wait for its end or call ~/jog_stop'
        return None

    def _here(self, t: float) -> TrajectorySample:
        """Where the reference stands at rest at time t (busy(t) is None)."""
        assert self.path is not None
        s = self.path.sample(t)
        return TrajectorySample(s.position, _STILL, _STILL, s.spindle)

    def _next_sample(self, t: float) -> float:
        T = self.machine.sample_period
        return (math.floor(t / T + 1e-9) + 1) * T

    # -- the commands --------------------------------------------------------------------
    def jog(self, axis: str, distance: float, t: float | None) -> Order:
        """Move one axis by a signed distance [m] at jog.speed."""
        i = AXIS_NAMES.index(axis) if axis in AXIS_NAMES else -1
        if i < 0:
            return Order(False, f'unknown axis {axis!r}: one of {", ".join(AXIS_NAMES)}')
        if not (math.isfinite(distance) and distance != 0.0):
            return Order(False, f'a jog needs a finite, non-zero distance [m], got {distance!r}')
        what = f'jog {axis} {1e3 * distance:+.3f} mm'
        why = self.busy(t)
        if why is not None:
            return Order(False, why)
        assert t is not None
        here = self._here(t)
        target = list(here.position)
        target[i] += distance
        beyond = self.machine.travel.outside(target)
        if beyond is not None:
            return Order(False, f'{what} would leave the machine travel: {beyond}')
        return self._move(what, [Piece(here.position, _point(target), self.machine.jog_speed)], t)

    def jog_continuous(self, axis: str, velocity: float, t: float | None) -> Order:
        """Move one axis at a signed velocity [m/s] toward the end of its travel, until
        jog_stop."""
        i = AXIS_NAMES.index(axis) if axis in AXIS_NAMES else -1
        if i < 0:
            return Order(False, f'unknown axis {axis!r}: one of {", ".join(AXIS_NAMES)}')
        if not (math.isfinite(velocity) and velocity != 0.0):
            return Order(False, f'a jog needs a finite, non-zero velocity [m/s], got {velocity!r}')
        top = self.machine.limits.velocity[i]
        if abs(velocity) > top:
            return Order(
                False,
                f'{1e3 * abs(velocity):g} mm/s is above the velocity limit of {axis}, '
                f'gcode.max_velocity {1e3 * top:g} mm/s',
            )
        why = self.busy(t)
        if why is not None:
            return Order(False, why)
        assert t is not None
        here = self._here(t)
        travel = self.machine.travel
        end = travel.maximum[i] if velocity > 0 else travel.minimum[i]
        name = 'travel.max' if velocity > 0 else 'travel.min'
        if not math.isfinite(end):
            return Order(False, f'{axis} has no end of travel to jog toward ({name} {end})')
        if (end - here.position[i]) * velocity <= 0.0:
            return Order(False, f'{axis} stands at {name} {end:g} m already')
        target = list(here.position)
        target[i] = end
        what = f'continuous jog of {axis} at {1e3 * velocity:+.3f} mm/s'
        return self._move(what, [Piece(here.position, _point(target), abs(velocity))], t)

    def go_home(self, t: float | None) -> Order:
        """A rapid to the home position."""
        why = self.busy(t)
        if why is not None:
            return Order(False, why)
        assert t is not None
        here = self._here(t)
        beyond = self.machine.travel.outside(self.home)
        if beyond is not None:
            return Order(False, f'home {_mm(self.home)} is outside the machine travel: {beyond}')
        return self._move(f'home to {_mm(self.home)}', [Piece(here.position, self.home)], t)

    def set_home(self, t: float | None) -> Order:
        """Where the reference stands becomes home."""
        why = self.busy(t)
        if why is not None:
            return Order(False, why)
        assert t is not None
        self.home = self._here(t).position
        return Order(True, f'home set to {_mm(self.home)}')

    def mdi(self, line: str, t: float | None) -> Order:
        """One G-code line, read and planned from where the reference stands, run at once."""
        if '\n' in line.strip() or '\r' in line.strip():
            return Order(False, 'MDI runs one line: the text holds several')
        if not line.strip():
            return Order(False, 'MDI needs a G-code line, got an empty one')
        why = self.busy(t)
        if why is not None:
            return Order(False, why)
        assert t is not None
        here = self._here(t)
        m = self.machine
        setup = replace(m.setup, home=self.home)
        try:
            moves = parse_program(line.strip(), MDI_FILE, here.position, m.work_offset, setup)
        except GcodeError as exc:
            return Order(False, str(exc))
        refused = _not_for_mdi(moves)
        if refused is not None:
            return Order(False, refused)
        tolerance = min([m.limits.tolerance, *(x.tolerance for x in moves if x.tolerance)])
        pieces, blocks = pieces_by_block(moves, tolerance)
        try:
            check_travel(pieces, [moves[b].where for b in blocks], m.travel)
        except GcodeError as exc:
            return Order(False, str(exc))
        return self._move(f'MDI {line.strip()!r}', pieces, t, tolerance)

    def jog_stop(self, t: float | None) -> Order:
        """Bring the move under way to rest along its path."""
        motion = self.motion
        if motion is None or t is None or motion.at_rest(t - self._start):
            return Order(False, 'nothing to stop: no jog, home or MDI move is under way')
        said = motion.stop()
        return Order(said.accepted, said.message)

    def _move(
        self, what: str, pieces: Sequence[Piece], t: float, tolerance: float | None = None
    ) -> Order:
        m = self.machine
        here = self._here(t)
        machine = m.limits if tolerance is None else replace(m.limits, tolerance=tolerance)
        # Room for the stop: the feed hold's share of acceleration and jerk.
        limits = machine.scaled(1.0, RESERVE)
        try:
            planned = plan(pieces, limits)
        except PlanError as exc:
            return Order(False, f'{what}: {exc}')
        if planned.end_time <= 0.0:
            return Order(
                True, f'{what}: nothing to move, the machine stands at {_mm(here.position)}'
            )
        # How fast the stop may take the speed down: the faster the path may run, the slower
        # (override_limit); no axis of it runs faster than its fastest piece.
        fastest = max(p.speed for p in pieces if not p.rest)
        velocity = tuple(min(v, fastest) for v in machine.velocity)
        limit = OverrideLimit.of(velocity, machine.acceleration, machine.jerk, 1.0, RESERVE)
        motion = Motion(planned, limit, m.sample_period, what, here.spindle)
        self._start = self._next_sample(t)
        self.path = Spliced(here, motion, self._start)
        self.motion = motion
        return Order(True, f'{what}: to {_mm(planned.end_point)} in {planned.end_time:.3f} s')


def _point(values: Sequence[float]) -> Point:
    return (float(values[0]), float(values[1]), float(values[2]))


def _not_for_mdi(moves: Sequence[Move]) -> str | None:
    """Why an MDI line's moves cannot run here (None: they can)."""
    for x in moves:
        if x.kind == 'stop' and x.pause:
            return f'{x.where}: a pause (M0, M1) in MDI has nothing to pause: leave it out'
        if x.kind == 'spindle':
            return (
                f'{x.where}: MDI does not change the spindle (M3, M4, M5, S): run it in a program'
            )
    return None
