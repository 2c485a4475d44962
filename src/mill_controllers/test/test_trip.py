"""Following-error trip: latched above the limit, brake request until reset."""

from __future__ import annotations

import math

import pytest
from mill_controllers.trip import FollowingErrorTrip


def test_latches_and_resets() -> None:
    trip = FollowingErrorTrip(1e-3)
    assert trip.command(0.0, 0.9e-3, 2.0) == 2.0
    assert trip.command(0.0, -0.9e-3, -2.0) == -2.0
    assert math.isnan(trip.command(0.5, -1.1e-3, 2.0))
    assert trip.trip is not None and trip.trip.time == 0.5 and trip.trip.error == -1.1e-3
    # latched: a small error again does not release it
    assert math.isnan(trip.command(0.6, 0.0, 2.0))
    cleared = trip.reset()
    assert cleared is not None and cleared.error == -1.1e-3
    assert trip.command(0.7, 0.0, 2.0) == 2.0


def test_a_new_limit_leaves_a_trip_latched() -> None:
    trip = FollowingErrorTrip(1e-3)
    assert math.isnan(trip.command(0.5, 1.5e-3, 2.0))
    for limit in (1e-3, 1.0, math.inf):  # the same value, a larger one, none at all
        trip.set_limit(limit)
        assert trip.limit == limit and trip.trip is not None and trip.trip.error == 1.5e-3
        assert math.isnan(trip.command(0.6, 0.0, 2.0))
    assert trip.reset() is not None and trip.command(0.7, 1e3, 2.0) == 2.0  # inf: no trip
    with pytest.raises(ValueError, match='following_error_limit'):
        trip.set_limit(0.0)
    assert trip.limit == math.inf


def test_infinite_limit_never_trips_and_bad_limits_are_refused() -> None:
    trip = FollowingErrorTrip(math.inf)
    assert trip.command(0.0, 1e9, 1.0) == 1.0
    assert not trip.check(0.0, math.nan)
    for bad in (0.0, -1.0, math.nan):
        with pytest.raises(ValueError, match='following_error_limit'):
            FollowingErrorTrip(bad)


def test_the_limit_grows_with_the_reference_speed_as_linuxcncs() -> None:
    # FERROR 1 mm at 50 mm/s, MIN_FERROR 0.2 mm at rest: 0.6 mm at 25 mm/s
    trip = FollowingErrorTrip(1e-3, 0.2e-3, 0.05)
    assert trip.limit_at(0.0) == pytest.approx(0.2e-3)
    assert trip.limit_at(-0.025) == pytest.approx(0.6e-3)
    assert trip.limit_at(0.2) == pytest.approx(1e-3)  # above the top speed: FERROR
    assert trip.command(0.0, 0.55e-3, 1.0, speed=0.025) == 1.0
    assert math.isnan(trip.command(0.1, 0.3e-3, 1.0, speed=0.0))  # at rest: 0.3 > 0.2 mm
    assert trip.trip is not None and trip.trip.limit == pytest.approx(0.2e-3)


def test_without_a_minimum_the_limit_is_fixed_at_every_speed() -> None:
    trip = FollowingErrorTrip(1e-3)
    assert trip.limit_at(0.0) == trip.limit_at(1.0) == 1e-3
    assert trip.command(0.0, 0.9e-3, 1.0, speed=0.0) == 1.0
    with pytest.raises(ValueError, match='min_following_error'):
        FollowingErrorTrip(1e-3, 2e-3, 0.05)
    with pytest.raises(ValueError, match='max_velocity'):
        FollowingErrorTrip(1e-3, 0.5e-3, 0.0)
