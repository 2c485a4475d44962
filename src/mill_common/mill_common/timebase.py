"""Sample times as integer nanoseconds, converted to seconds in exactly one way.

The distributed graph and the offline simulator must compute identical float
times from the same step, so both go through these functions.
"""

from __future__ import annotations

import math
from typing import Protocol


class TimeFields(Protocol):
    """A builtin_interfaces/Time or Duration message: rclpy's, rosbags', mill_common.codec's."""

    @property
    def sec(self) -> int: ...

    @property
    def nanosec(self) -> int: ...


def stamp_ns(sec: int, nanosec: int) -> int:
    """A builtin_interfaces/Time (or Duration) given by its two fields, in nanoseconds."""
    return sec * 1_000_000_000 + nanosec


def time_ns(time: TimeFields) -> int:
    """A builtin_interfaces/Time or Duration message (a header's stamp, a point's
    time_from_start) in nanoseconds: stamp_ns of its fields, written out (the nodes call this
    for every message they take, and a second call costs a third more)."""
    return time.sec * 1_000_000_000 + time.nanosec


def period_ns(period_s: float) -> int:
    """Sample period in whole nanoseconds; ValueError unless it is positive and exact to 1 ns."""
    ns = round(period_s * 1e9)
    if ns <= 0 or abs(ns - period_s * 1e9) > 1e-3:
        raise ValueError(f'sample period must be a positive whole number of ns, got {period_s!r} s')
    return ns


def step_ns(k: int, dt_ns: int) -> int:
    """Stamp of sample k in nanoseconds."""
    return k * dt_ns


# The longest job (machine time) a trajectory is given: a day. Every sample of a run is
# kept in memory (about 0.2 kB at 1 kHz: 20 GB a day), so a longer one is refused.
MAX_JOB_TIME = 86_400.0  # s


def job_steps(end_time: float, dt_ns: int) -> int:
    """Samples of a job: k = 0 .. the first k with t_k >= end_time (when the job is done);
    ValueError for an end time that is not finite or beyond MAX_JOB_TIME."""
    if not math.isfinite(end_time) or end_time > MAX_JOB_TIME:
        raise ValueError(f'a job ending at t = {end_time:g} s: longer than {MAX_JOB_TIME:g} s')
    k = max(0, math.ceil(end_time * 1e9 / dt_ns) - 1)
    while seconds(k * dt_ns) < end_time:
        k += 1
    while k > 0 and seconds((k - 1) * dt_ns) >= end_time:
        k -= 1
    return k + 1


def seconds(ns: int) -> float:
    """Time in seconds of a stamp in nanoseconds."""
    return ns / 1e9


def sample_stamp_ns(k: int, period_s: float) -> int:
    """Stamp of sample k for a period that is no whole number of ns (one spindle turn):
    the nearest ns to k·T, without drift."""
    return round(k * period_s * 1e9)


def sample_index(ns: int, period_s: float) -> int:
    """The sample k whose stamp (sample_stamp_ns) is ns."""
    return round(ns / (period_s * 1e9))


def control_instant(j: int, control_period_s: float, dt_ns: int) -> int:
    """Sample index (on a grid of dt_ns) of control instant j of a slower controller: the
    first sample stamped at or after its instant j·T_c (sample_stamp_ns), which is where a
    controller acting on the first sample of each period acts."""
    return -(-sample_stamp_ns(j, control_period_s) // dt_ns)
