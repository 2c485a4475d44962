"""The trajectory's schedules: which reference points answer a tick, an override, the clock."""

from __future__ import annotations

import pytest
from mill_common.timebase import seconds
from mill_trajectory.approach import ApproachError
from mill_trajectory.base import TrajectorySample
from mill_trajectory.feed_override import FeedOverride, TimeScaledPath
from mill_trajectory.linear_path import LinearPath
from mill_trajectory.schedule import ClockedReference, JobProgress, WallClockReference

DT = 1_000_000


def path() -> LinearPath:
    return LinearPath.from_parameters({s.name: s.default for s in LinearPath.PARAMETERS})


def test_a_tick_is_answered_with_the_path_sampled_on_the_grid_ahead() -> None:
    p = path()
    ref = ClockedReference(p, DT, 20)
    points = ref.answer(10 * DT)
    assert points is not None and points.stamps() == [(10 + i) * DT for i in range(20)]
    assert points.samples[3] == p.sample(seconds(13 * DT))


def test_with_an_override_each_sample_is_sent_once_in_order() -> None:
    override = FeedOverride(0.0, 2.0)
    ref = ClockedReference(path(), DT, 20, TimeScaledPath(path(), 1e-3), override)
    first = ref.answer(0)
    assert first is not None and len(first.samples) == 20
    second = ref.answer(10 * DT)  # samples 20 .. 29: 10 .. 19 went out already
    assert second is not None and second.stamp_ns == 20 * DT and len(second.samples) == 10


def test_the_wall_clock_holds_then_runs_on_the_grid_of_the_newest_state() -> None:
    p = path()
    start = p.sample(0.0).position
    wall = WallClockReference(p, DT, 5)
    with pytest.raises(ApproachError, match='stands'):
        wall.hold([start[0] + 1.0, start[1], start[2]], [0, 1, 2], 0, 0.002, 0.02)
    here = [start[0] + 1e-4, start[1], start[2]]
    approach = wall.hold(here, [0, 1, 2], 7_000_123, 0.002, 0.02)
    held = wall.holding(7_000_123 + 3 * DT + 10)
    assert held.stamp_ns == 7_000_123 + 2 * DT
    assert held.samples[0] == TrajectorySample(tuple(here), (0, 0, 0), (0, 0, 0))
    t0 = wall.start(7_000_123 + 4 * DT + 5)
    assert t0 == 7_000_123 + 4 * DT and approach.duration > 0
    assert wall.running(t0 + 3 * DT).stamp_ns == t0 + 2 * DT


def test_progress_is_reported_once_a_second_and_done_once() -> None:
    job = JobProgress(2.0)
    assert job.update(0.0) == 'running'
    assert job.update(0.5) is None
    assert job.update(1.0) == 'running'
    assert job.update(2.0) == 'done' and job.done_at == 2.0
    assert job.update(2.5) is None
