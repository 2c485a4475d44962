"""Parameters of the trajectory node and how they build the trajectory core. ROS-free.

The offline simulator builds the same core from the same scenario file through here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from mill_common.parameters import (
    ParamSpec,
    algorithm_values,
    boolean,
    in_range,
    input_watch_specs,
    non_negative,
    non_negative_int,
    number_list,
    one_of,
    positive,
)
from mill_common.signals import AXES
from mill_common.timebase import period_ns, seconds

from mill_trajectory.base import Trajectory
from mill_trajectory.feed_override import (
    FeedOverride,
    JobEnd,
    PeriodicOverridePath,
    TimeScaledPath,
)
from mill_trajectory.gcode_program import GcodeTrajectory
from mill_trajectory.planner import xyz
from mill_trajectory.registry import TRAJECTORIES
from mill_trajectory.schedule import (
    ClockedReference,
    JobProgress,
    OverrideReference,
    WallClockReference,
)
from mill_trajectory.toolpath import Travel


def parameter_specs() -> list[tuple[str, ParamSpec]]:
    specs = [
        ('trajectory', ParamSpec('trajectory', 'linear', 'path type', TRAJECTORIES.check())),
        (
            'duration',
            ParamSpec(
                'duration',
                0.0,
                'end the job after this time [s]; 0 = when the path ends',
                non_negative,
            ),
        ),
        (
            'sample_period',
            ParamSpec(
                'sample_period', 0.001, 'sample period T [s]', in_range(1e-6, 1.0), read_only=True
            ),
        ),
        (
            'preview_time',
            ParamSpec(
                'preview_time',
                0.02,
                'span of reference points sent per /clock tick [s]; must cover the '
                "plant's clock_period",
                in_range(1e-6, 10.0),
            ),
        ),
        (
            'settle_time',
            ParamSpec('settle_time', 0.0, 'time held at the end of the path [s]', non_negative),
        ),
    ]
    specs += [
        (
            'timing',
            ParamSpec(
                'timing',
                'lockstep',
                'lockstep: answer each /clock tick of the plant with the reference ahead of it; '
                'realtime: once every axis of `axes` has reported its position, hold the axes '
                'where they stand until every axis has a command, then start the job, first '
                'moving to its start (approach.*), and publish the reference on the system '
                'clock every publish_period',
                one_of('lockstep', 'realtime'),
                read_only=True,
            ),
        ),
        (
            'axes',
            ParamSpec(
                'axes',
                ['x', 'y', 'z'],
                'realtime: the axes whose states start the job',
                _axes,
                read_only=True,
            ),
        ),
        (
            'min_subscribers',
            ParamSpec(
                'min_subscribers',
                0,
                'realtime: readers the reference needs before the job starts, at least one '
                'per axis (the controllers); run_scenario adds its monitor, so that the record '
                'has the job from its start',
                non_negative_int,
                read_only=True,
            ),
        ),
        (
            'publish_period',
            ParamSpec(
                'publish_period',
                0.01,
                'realtime: wall time between reference messages [s]; each covers preview_time '
                'ahead',
                in_range(1e-4, 1.0),
                read_only=True,
            ),
        ),
        (
            'approach.speed',
            ParamSpec(
                'speed',
                0.002,
                'realtime: peak speed of the move from where the axes stand to the start point '
                '[m/s]',
                positive,
                read_only=True,
            ),
        ),
        (
            'approach.max_distance',
            ParamSpec(
                'max_distance',
                0.02,
                'realtime: refuse to start when an axis stands further than this from the start '
                'point [m]',
                non_negative,
                read_only=True,
            ),
        ),
        (
            'feed_override.enabled',
            ParamSpec(
                'enabled',
                False,
                'follow /mill/feed_override: the path speed is scaled by the latest override '
                '(the reference is then sent for one clock period at a time)',
                boolean,
                read_only=True,
            ),
        ),
        (
            'feed_override.lockstep',
            ParamSpec(
                'lockstep',
                False,
                'answer each /mill/feed_override stamped t_k with the reference of sample k '
                '(one point, with the override ramp of a β-hold) instead of answering /clock; '
                'for a force controller in lockstep with its plant',
                boolean,
                read_only=True,
            ),
        ),
        (
            'feed_override.period',
            ParamSpec(
                'period',
                0.0,
                'with lockstep: the control period T_c of the override sender [s]. 0 = one '
                'override per sample, answered with that sample (a force job, one sample per '
                'spindle revolution); > 0 = one override per period, at the first sample at or '
                'after each j T_c, which sets the reference from that sample up to the next '
                'control instant (a force controller on a faster axis job)',
                non_negative,
                read_only=True,
            ),
        ),
        (
            'feed_override.min',
            ParamSpec('min', 0.0, 'smallest accepted feed override [-]', in_range(0.0, 10.0)),
        ),
        (
            'feed_override.max',
            ParamSpec('max', 1.5, 'largest accepted feed override [-]', in_range(0.0, 10.0)),
        ),
        (
            'travel.min',
            ParamSpec(
                'min',
                [-1.0, -1.0, -1.0],
                "the machine's travel: lowest x, y, z the reference may reach [m]; a path "
                'that leaves the travel is refused before anything moves',
                number_list(3),
            ),
        ),
        (
            'travel.max',
            ParamSpec(
                'max', [1.0, 1.0, 1.0], "the machine's travel: highest x, y, z [m]", number_list(3)
            ),
        ),
        *input_watch_specs(),
    ]
    return specs + TRAJECTORIES.parameter_specs()


def _axes(value: Any) -> str | None:
    if not isinstance(value, list | tuple) or not value:
        return 'must be a non-empty list of axis names'
    bad = [a for a in value if a not in AXES]
    return f'must name axes among {", ".join(AXES)}, got {bad[0]!r}' if bad else None


@dataclass(frozen=True)
class Job:
    trajectory: Trajectory
    end_time: float  # the job is over at this time [s]


def build_job(values: dict[str, Any]) -> Job:
    """The job's path, checked against the travel (ValueError naming where it leaves it)."""
    cls = TRAJECTORIES.get(values['trajectory'])
    own = algorithm_values(cls, values)
    travel = Travel(xyz(values['travel.min']), xyz(values['travel.max']))
    if any(lo > hi for lo, hi in zip(travel.minimum, travel.maximum, strict=True)):
        raise ValueError('travel.min must not exceed travel.max on any axis')
    path: Trajectory
    if cls is GcodeTrajectory:
        # Planned so that no feed override up to feed_override.max breaks a limit.
        headroom = values['feed_override.max'] if values['feed_override.enabled'] else None
        path = GcodeTrajectory.from_parameters(own, travel, headroom)
    else:
        path = cls.from_parameters(own)
        check_path_travel(path, travel, values['sample_period'])
    end = path.end_time + values['settle_time']
    if values['duration'] > 0:
        end = min(end, values['duration'])
    return Job(path, end)


def check_path_travel(path: Trajectory, travel: Travel, sample_period: float) -> None:
    """ValueError if the path's box (Trajectory.bounds) reaches outside the travel."""
    lo, hi = path.bounds(sample_period)
    problem = travel.outside(lo) or travel.outside(hi)
    if problem:
        raise ValueError(f'the path leaves the machine travel: {problem}')


def preview_samples(values: dict[str, Any], dt_ns: int) -> int:
    """Samples of reference sent per /clock tick (lockstep), at least one."""
    return max(1, math.ceil(values['preview_time'] * 1e9 / dt_ns))


Schedule = ClockedReference | OverrideReference | WallClockReference


def build_schedule(values: dict[str, Any], override: FeedOverride) -> tuple[Schedule, JobProgress]:
    """What paces the node and which points it sends, with its end rule."""
    job = build_job(values)
    path, T = job.trajectory, values['sample_period']
    # A planned path (G-code) limits how fast the override may change.
    limit = path.override_limit if isinstance(path, GcodeTrajectory) else None
    enabled, paced = values['feed_override.enabled'], values['feed_override.lockstep']
    if paced and not enabled:
        raise ValueError('feed_override.lockstep needs feed_override.enabled')
    if enabled and values['timing'] == 'realtime':
        raise ValueError('feed_override is not available with timing realtime')
    if paced and not values['feed_override.period'] > 0:
        # The force job: samples are stamped by the override's sender (T need not be whole ns).
        scaled = TimeScaledPath(path, T, limit=limit)
        return OverrideReference(scaled, override, T), JobProgress(job.end_time)
    dt_ns = period_ns(T)
    end = JobEnd.of(path.end_time, values['settle_time'], values['duration'], dt_ns)
    if paced:
        period = values['feed_override.period']
        periodic = PeriodicOverridePath(path, dt_ns, period, override, end, limit)
        reference = OverrideReference(periodic.scaled, override, T, periodic)
        return reference, JobProgress(job.end_time, periodic.scaled, dt_ns)
    preview = preview_samples(values, dt_ns)
    if values['timing'] == 'realtime':
        count = preview + math.ceil(values['publish_period'] * 1e9 / dt_ns) + 2
        return WallClockReference(path, dt_ns, count), JobProgress(job.end_time)
    timed = TimeScaledPath(path, seconds(dt_ns), end, limit) if enabled else None
    clocked = ClockedReference(path, dt_ns, preview, timed, override)
    return clocked, JobProgress(job.end_time, timed, dt_ns)
