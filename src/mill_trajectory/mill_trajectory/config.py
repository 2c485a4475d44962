"""Parameters of the trajectory node and how they build the trajectory core. ROS-free.

The offline simulator builds the same core from the same scenario file through here.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

from mill_common.declared import ParamSet, param
from mill_common.node_params import InputWatch
from mill_common.parameters import (
    ParameterError,
    ParamSpec,
    algorithm_values,
    boolean,
    in_range,
    non_negative,
    non_negative_int,
    one_of,
    positive,
)
from mill_common.signals import AXES
from mill_common.timebase import MAX_JOB_TIME, period_ns, seconds
from mill_common.travel import MachineTravel

from mill_trajectory.base import Trajectory
from mill_trajectory.feed_override import (
    FeedOverride,
    JobEnd,
    PeriodicOverridePath,
    TimeScaledPath,
)
from mill_trajectory.gcode_program import (
    GcodeParams,
    GcodeTrajectory,
    gcode_setup,
    machine_limits,
)
from mill_trajectory.gcode_words import GcodeError
from mill_trajectory.hold import Holds
from mill_trajectory.manual import Machine
from mill_trajectory.planner import xyz
from mill_trajectory.registry import TRAJECTORIES
from mill_trajectory.schedule import (
    ClockedReference,
    JobProgress,
    OverrideReference,
    WallClockReference,
)
from mill_trajectory.toolpath import Travel


def _axes(value: Any) -> str | None:
    if not isinstance(value, list | tuple) or not value:
        return 'must be a non-empty list of axis names'
    bad = [a for a in value if a not in AXES]
    return f'must name axes among {", ".join(AXES)}, got {bad[0]!r}' if bad else None


@dataclass(frozen=True)
class TrajectoryNodeParams(InputWatch):
    """The trajectory node's own parameters (the groups approach.*, feed_override.* and
    travel.* are sets of their own)."""

    trajectory: str = param('linear', 'path type', TRAJECTORIES.check())
    duration: float = param(
        0.0,
        'end the job after this time [s]; 0 = when the path ends',
        in_range(0.0, MAX_JOB_TIME),
    )
    sample_period: float = param(
        0.001, 'sample period T', in_range(1e-6, 1.0), unit='s', read_only=True
    )
    preview_time: float = param(
        0.02,
        "span of reference points sent per /clock tick [s]; must cover the plant's clock_period",
        in_range(1e-6, 10.0),
    )
    settle_time: float = param(
        0.0, 'time held at the end of the path', in_range(0.0, MAX_JOB_TIME), unit='s'
    )
    timing: str = param(
        'lockstep',
        'lockstep: answer each /clock tick of the plant with the reference ahead of it; '
        'realtime: once every axis of `axes` has reported its position, hold the axes '
        'where they stand until every axis has a command, then start the job, first '
        'moving to its start (approach.*), and publish the reference on the system '
        'clock every publish_period',
        one_of('lockstep', 'realtime'),
        read_only=True,
    )
    axes: list[str] = param(
        ['x', 'y', 'z'], 'realtime: the axes whose states start the job', _axes, read_only=True
    )
    min_subscribers: int = param(
        0,
        'realtime: readers the reference needs before the job starts, at least one '
        'per axis (the controllers); run_scenario adds its monitor, so that the record '
        'has the job from its start',
        non_negative_int,
        read_only=True,
    )
    publish_period: float = param(
        0.01,
        'realtime: wall time between reference messages [s]; each covers preview_time ahead',
        in_range(1e-4, 1.0),
        read_only=True,
    )


@dataclass(frozen=True)
class ApproachParams(ParamSet):
    """realtime: the move from where the axes stand to the start point."""

    PREFIX: ClassVar[str] = 'approach'
    speed: float = param(
        0.002,
        'realtime: peak speed of the move from where the axes stand to the start point',
        positive,
        unit='m/s',
        read_only=True,
    )
    max_distance: float = param(
        0.02,
        'realtime: refuse to start when an axis stands further than this from the start point',
        non_negative,
        unit='m',
        read_only=True,
    )


@dataclass(frozen=True)
class JogParams(ParamSet):
    """realtime, between jobs: moving the machine by hand (mill_trajectory.manual)."""

    PREFIX: ClassVar[str] = 'jog'
    speed: float = param(
        0.005,
        'realtime: speed of a jog by increment (~/jog); the axis limits gcode.max_* bound it '
        'and every manual move',
        positive,
        unit='m/s',
        read_only=True,
    )


@dataclass(frozen=True)
class FeedOverrideParams(ParamSet):
    """Following /mill/feed_override."""

    PREFIX: ClassVar[str] = 'feed_override'
    enabled: bool = param(
        False,
        'follow /mill/feed_override: the path speed is scaled by the latest override '
        '(the reference is then sent for one clock period at a time)',
        boolean,
        read_only=True,
    )
    lockstep: bool = param(
        False,
        'answer each /mill/feed_override stamped t_k with the reference of sample k '
        '(one point, with the override ramp of a β-hold) instead of answering /clock; '
        'for a force controller in lockstep with its plant',
        boolean,
        read_only=True,
    )
    period: float = param(
        0.0,
        'with lockstep: the control period T_c of the override sender [s]. 0 = one '
        'override per sample, answered with that sample (a force job, one sample per '
        'spindle revolution); > 0 = one override per period, at the first sample at or '
        'after each j T_c, which sets the reference from that sample up to the next '
        'control instant (a force controller on a faster axis job)',
        non_negative,
        read_only=True,
    )
    min: float = param(0.0, 'smallest accepted feed override', in_range(0.0, 10.0), unit='-')
    max: float = param(1.5, 'largest accepted feed override', in_range(0.0, 10.0), unit='-')

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.min > self.max:
            raise ParameterError('feed_override.min', self.min, 'must not exceed feed_override.max')
        if self.lockstep and not self.enabled:
            raise ParameterError(
                'feed_override.lockstep', True, 'feed_override.lockstep needs feed_override.enabled'
            )


@dataclass(frozen=True)
class TravelParams(MachineTravel):
    """The machine's travel (mill_common.travel: the drive reads the same declaration)."""

    @property
    def travel(self) -> Travel:
        return Travel(xyz(self.min), xyz(self.max))


def parameter_specs() -> list[tuple[str, ParamSpec]]:
    return [
        *TrajectoryNodeParams.named_specs(),
        *ApproachParams.named_specs(),
        *JogParams.named_specs(),
        *FeedOverrideParams.named_specs(),
        *TravelParams.named_specs(),
        *TRAJECTORIES.parameter_specs(),
    ]


@dataclass(frozen=True)
class JobPath:
    trajectory: Trajectory
    end_time: float  # the job is over at this time [s]


def build_job(values: Mapping[str, Any]) -> JobPath:
    """The job's path, checked against the travel (ValueError naming where it leaves it)."""
    node = TrajectoryNodeParams.from_node_values(values)
    override = FeedOverrideParams.from_node_values(values)
    travel = TravelParams.from_node_values(values).travel
    cls = TRAJECTORIES.get(node.trajectory)
    own = algorithm_values(cls, values)
    path: Trajectory
    if cls is GcodeTrajectory:
        # Planned so that no feed override up to feed_override.max breaks a limit.
        headroom = override.max if override.enabled else None
        path = GcodeTrajectory.from_parameters(own, travel, headroom)
    else:
        path = cls.from_parameters(own)
        check_path_travel(path, travel, node.sample_period)
    end = path.end_time + node.settle_time
    if node.duration > 0:
        end = min(end, node.duration)
    if not end <= MAX_JOB_TIME:  # a path that takes longer (a feed of nm/s): its samples
        raise ValueError(
            f'the job would end at t = {end:g} s, after {MAX_JOB_TIME:g} s (a day): '
            'give a duration or a faster path'
        )
    return JobPath(path, end)


def check_path_travel(path: Trajectory, travel: Travel, sample_period: float) -> None:
    """ValueError if the path's box (Trajectory.bounds) reaches outside the travel."""
    lo, hi = path.bounds(sample_period)
    problem = travel.outside(lo) or travel.outside(hi)
    if problem:
        raise ValueError(f'the path leaves the machine travel: {problem}')


def manual_machine(values: Mapping[str, Any]) -> Machine:
    """What manual moves (jog, home, MDI) are planned within: the planner's limits, the
    travel, the jog speed, and the G-code setup an MDI line reads with."""
    node = TrajectoryNodeParams.from_node_values(values)
    gcode = GcodeParams.from_values(algorithm_values(GcodeTrajectory, values))
    try:
        setup = gcode_setup(gcode)
    except GcodeError as exc:
        raise ParameterError('gcode.tool_table', gcode.tool_table, str(exc)) from None
    return Machine(
        machine_limits(gcode),
        TravelParams.from_node_values(values).travel,
        node.sample_period,
        JogParams.from_node_values(values).speed,
        setup,
        xyz(gcode.work_offset),
    )


def preview_samples(values: Mapping[str, Any], dt_ns: int) -> int:
    """Samples of reference sent per /clock tick (lockstep), at least one."""
    preview_time = TrajectoryNodeParams.from_node_values(values).preview_time
    return max(1, math.ceil(preview_time * 1e9 / dt_ns))


Schedule = ClockedReference | OverrideReference | WallClockReference


def build_schedule(
    values: Mapping[str, Any], override: FeedOverride
) -> tuple[Schedule, JobProgress]:
    """What paces the node and which points it sends, with its end rule."""
    node = TrajectoryNodeParams.from_node_values(values)
    feed = FeedOverrideParams.from_node_values(values)  # lockstep needs enabled
    job = build_job(values)
    path, T = job.trajectory, node.sample_period
    # A planned path (G-code) limits how fast the override may change.
    limit = path.override_limit if isinstance(path, GcodeTrajectory) else None
    enabled, paced = feed.enabled, feed.lockstep
    if enabled and node.timing == 'realtime':
        raise ValueError('feed_override is not available with timing realtime')
    holds = job_holds(path, T, enabled and limit is not None)
    if holds is not None and node.timing == 'realtime':
        first = holds.pauses[0]
        raise ValueError(
            f'{first.where}: {first.text}: timing realtime does not pause yet; '
            'run it in lockstep or set gcode.optional_stop false for M1'
        )
    if paced and not feed.period > 0:
        # The force job: samples are stamped by the override's sender (T need not be whole ns).
        scaled = TimeScaledPath(path, T, limit=limit, holds=holds)
        return OverrideReference(scaled, override, T), JobProgress(job.end_time)
    dt_ns = period_ns(T)
    end = JobEnd.of(path.end_time, node.settle_time, node.duration, dt_ns)
    if paced:
        periodic = PeriodicOverridePath(path, dt_ns, feed.period, override, end, limit)
        periodic.scaled.holds = holds
        reference = OverrideReference(periodic.scaled, override, T, periodic)
        return reference, JobProgress(job.end_time, periodic.scaled, dt_ns)
    preview = preview_samples(values, dt_ns)
    if node.timing == 'realtime':
        count = preview + math.ceil(node.publish_period * 1e9 / dt_ns) + 2
        return WallClockReference(path, dt_ns, count), JobProgress(job.end_time)
    # A program that pauses runs on its own time too: its end is found where its path ends.
    timed = (
        TimeScaledPath(path, seconds(dt_ns), end, limit, holds)
        if enabled or holds is not None
        else None
    )
    clocked = ClockedReference(path, dt_ns, preview, timed, override if enabled else None)
    return clocked, JobProgress(job.end_time, timed, dt_ns)


def job_holds(path: Trajectory, sample_period: float, can_hold: bool) -> Holds | None:
    """The pauses and feed hold of a G-code job (None: a path that never pauses)."""
    if not isinstance(path, GcodeTrajectory):
        return None
    why = (
        None
        if can_hold
        else 'feed hold needs feed_override.enabled: only then does the plan leave the '
        'acceleration and jerk to decelerate along the path within the limits'
    )
    holds = Holds(path.pauses, sample_period, path.resume_after, why)
    return holds if path.pauses or can_hold else None
