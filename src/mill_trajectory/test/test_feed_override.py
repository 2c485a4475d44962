"""Feed override: clamped, held over NaN, and the path time runs at the override's rate."""

from __future__ import annotations

import math

import pytest
from mill_trajectory.feed_override import FeedOverride, TimeScaledPath
from mill_trajectory.linear_path import LinearPath

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
    path = LinearPath([(0.0, 0.0, 0.0), (0.1, 0.0, 0.0)], feed_rate=0.01)
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
