"""The drive's own motion checks: a speed limit always, a window around where the commands
ended while they are late (at this tick and extrapolated to the next)."""

from __future__ import annotations

from mill_plant.motion_guard import MotionGuard

T = 10_000_000  # [ns]


def run(guard: MotionGuard, xs: list[float], holding_from: int) -> list[dict[str, str]]:
    """x at ticks k·T, holding from tick holding_from on; the stops of every tick."""
    return [guard.check(k * T, {'x': x}, {'x': k >= holding_from}) for k, x in enumerate(xs)]


def held(a: float, v0: float = 0.003, n: int = 12) -> list[float]:
    """3 mm/s under fresh commands to tick 4 (the last fresh one: tick 3, whose command acts
    to tick 4); from tick 4 a held command accelerates the axis at a."""
    xs = [v0 * k * 0.01 for k in range(5)]
    for k in range(1, n):
        t = k * 0.01
        xs.append(xs[4] + v0 * t + 0.5 * a * t * t)
    return xs


def test_a_held_command_that_accelerates_the_axis_is_stopped_before_it_leaves_the_window() -> None:
    for a in (2.0, 5.0, 10.0, 40.0):
        guard = MotionGuard(['x'], speed_limit=10.0, hold_deviation=0.5e-3)
        xs = held(a)
        stops = run(guard, xs, holding_from=4)
        first = next(k for k, s in enumerate(stops) if s)
        assert 'around its course when its commands ended' in stops[first]['x']

        def off(k: int, xs: list[float] = xs) -> float:  # from the course at 3 mm/s since
            return abs(xs[k] - (xs[3] + 0.003 * (k - 3) * 0.01))  # the last fresh tick, 3

        # The bound: the window plus what the change of acceleration moves it in a period.
        assert off(first) <= 0.5e-3 + 0.5 * a * 0.01**2, a
        if 0.5 * a * 0.01**2 < 0.5e-3:  # the extrapolation sees the exit a period ahead
            assert off(first) <= 0.5e-3 < off(first + 1), a


def test_a_hold_on_course_goes_on_at_speed() -> None:
    guard = MotionGuard(['x'], speed_limit=1.0, hold_deviation=0.5e-3)
    xs = [0.05 * k * 0.01 for k in range(12)]  # 50 mm/s: 5 mm in ten held periods
    assert not any(run(guard, xs, holding_from=2))


def test_the_speed_limit_stops_an_axis_with_fresh_commands() -> None:
    guard = MotionGuard(['x', 'y'], speed_limit=0.1, hold_deviation=0.5e-3)
    assert guard.check(0, {'x': 0.0, 'y': 0.0}, {}) == {}
    stops = guard.check(T, {'x': 0.0015, 'y': 0.0005}, {})  # 150 and 50 mm/s
    assert list(stops) == ['x'] and 'speed 150.0 mm/s above the limit 100 mm/s' in stops['x']


def test_an_axis_left_out_starts_afresh() -> None:
    guard = MotionGuard(['x'], speed_limit=0.1, hold_deviation=0.5e-3)
    guard.check(0, {'x': 0.0}, {})
    guard.check(T, {}, {})  # stopped or not under way: forgotten
    assert guard.check(2 * T, {'x': 0.5}, {'x': True}) == {}  # no speed from a stale sample
