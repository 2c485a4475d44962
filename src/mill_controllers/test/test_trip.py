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
