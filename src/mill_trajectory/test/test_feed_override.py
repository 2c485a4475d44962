"""Feed override: clamped, held over NaN, and the path time runs at the override's rate."""

from __future__ import annotations

import math

import pytest
from mill_trajectory.feed_override import FeedOverride, TimeScaledPath
from mill_trajectory.linear_path import LinearParams, LinearPath

T = 1e-3


def test_out_of_range_is_clamped_and_nan_holds() -> None:
    fo = FeedOverride(0.0, 1.5)
    assert fo.accept(0.8).value == 0.8 and fo.accept(0.8).problem is None
    high = fo.accept(3.0)
    assert high.value == 1.5 and 'outside' in high.problem
    held = fo.accept(math.nan)
    assert held.value == 1.5 and 'non-finite' in held.problem
    assert fo.accept(-1.0).value == 0.0
    with pytest.raises(ValueError):
        FeedOverride(1.0, 0.5)


def test_path_time_advances_by_the_override() -> None:
    path = LinearPath(LinearParams(waypoints=[0.0, 0.0, 0.0, 0.1, 0.0, 0.0], feed_rate=0.01))
    scaled = TimeScaledPath(path, T)
    for _ in range(1000):
        s = scaled.sample(0.5)
    # 1000 samples at half feed: 0.5 s of path time, 5 mm along x, at 5 mm/s
    assert scaled.path_time == pytest.approx(0.5, rel=1e-12)
    assert s.position[0] == pytest.approx(0.01 * 0.4995, rel=1e-9)  # sampled at τ = 0.4995 s
    assert s.velocity[0] == pytest.approx(0.005, rel=1e-12)
    stop = scaled.sample(0.0)
    assert stop.velocity[0] == 0.0 and scaled.path_time == pytest.approx(0.5, rel=1e-12)


def test_a_ramping_override_adds_its_slope_to_the_acceleration() -> None:
    from mill_trajectory.program import ProgramTrajectory

    path = ProgramTrajectory.from_parameters(
        {'start': [0.0, 0.0, 0.0], 'segments': ['linear 1.0 0 0 0.01']}
    )
    scaled = TimeScaledPath(path, 0.1)
    s0 = scaled.sample(0.5, 2.0)  # o = 0.5 + 2τ over the sample (a β-hold ramp)
    assert s0.velocity[0] == pytest.approx(0.005) and s0.acceleration[0] == pytest.approx(0.02)
    # the path time advanced by ∫ o dτ = 0.5·0.1 + 2·0.1²/2
    assert scaled.path_time == pytest.approx(0.06)
    assert scaled.sample(0.7).position[0] == pytest.approx(0.01 * 0.06)


def _program(*segments: str):
    from mill_trajectory.program import ProgramTrajectory

    return ProgramTrajectory.from_parameters({'start': [0.0, 0.0, 0.0], 'segments': list(segments)})


def test_the_job_ends_when_the_path_ends_whatever_the_override() -> None:
    from mill_trajectory.feed_override import JobEnd

    path = _program('linear 0.01 0 0 0.01')  # 1 s of path at override 1
    end = JobEnd.of(path.end_time, 0.1, 0.0, 1_000_000)
    assert end.settle_samples == 100 and end.cap is None
    scaled = TimeScaledPath(path, T, end)
    k = 0
    while scaled.last_sample is None:
        scaled.sample(0.25)
        k += 1
    # 4 s of machine time at a quarter of the feed: τ(k) = k T / 4 reaches 1 s at k = 4000
    # (to the rounding of the sum of 0.25e-3 steps: one sample either way)
    assert abs(scaled.last_sample - (4000 + 100)) <= 1
    capped = TimeScaledPath(path, T, JobEnd.of(path.end_time, 0.1, 0.5, 1_000_000))
    for _ in range(501):
        capped.sample(0.25)
    assert capped.last_sample == 500  # the duration ends it first: t = 0.5 s


def test_periodic_override_sets_the_samples_up_to_the_next_control_instant() -> None:
    from mill_trajectory.feed_override import PeriodicOverridePath

    path = _program('linear 0.1 0 0 0.003')
    period = 1 / 30  # one revolution at 1800 rpm: 33.3 samples of 1 ms
    lock = PeriodicOverridePath(path, 1_000_000, period, FeedOverride(0.0, 2.0))
    assert [lock.instant(j) for j in range(4)] == [0, 34, 67, 100]
    a = lock.answer(0, 0.5, 0.0)
    assert a.first == 0 and len(a.samples) == 34 and a.problem is None
    assert all(s.velocity[0] == pytest.approx(0.0015) for s in a.samples)
    b = lock.answer(34, 5.0, 3.0)  # clamped to 2: no ramp
    assert b.first == 34 and len(b.samples) == 33 and 'outside' in b.problem
    assert b.samples[-1].velocity[0] == pytest.approx(0.006)
    c = lock.answer(67, 1.0, 30.0)  # a β-hold ramp: o = 1 + 30 i T over the period
    assert [s.velocity[0] for s in c.samples[:3]] == pytest.approx([0.003, 0.00309, 0.00318])
    assert c.samples[0].acceleration[0] == pytest.approx(30.0 * 0.003)
    late = lock.answer(200, 1.0, 0.0)  # a gap: it sets the samples from the first unset one
    assert late.first == 100 and 'expected 100' in late.problem
    assert lock.next_sample == lock.instant(7)
