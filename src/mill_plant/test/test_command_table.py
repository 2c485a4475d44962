"""The drive's command table: zero-order hold, late periods, a latched stop after N, release
only by the owner's re-arm (brake request, then a valid command) or the operator."""

from __future__ import annotations

import math

from mill_plant.command_table import CommandTable

T = 10_000_000  # [ns]


def test_before_the_first_command_an_axis_is_braked_and_not_counted_late() -> None:
    table = CommandTable(['x', 'y'], brake_after=3)
    for _ in range(5):
        tick = table.take()
        assert all(math.isnan(e) for e in tick.efforts)
        assert tick.stopped == [] and tick.resumed == []
    assert math.isnan(table.late_fraction('x'))  # no tick counted before the job started


def late_ticks_stop(table: CommandTable) -> None:
    """x's first command, then ticks without one until the third late tick stops it."""
    assert table.offer('x', 0, 1.5, arrived_ns=2_000_000)
    tick = table.take()
    assert tick.efforts == [1.5] and tick.resumed == ['x']  # released by its first command
    # Two ticks without a fresh command: the last one is held (zero-order hold).
    assert table.take().efforts == [1.5]
    assert table.take().efforts == [1.5]
    # The third late tick in a row stops the axis, once.
    tick = table.take()
    assert math.isnan(tick.efforts[0]) and tick.stopped == ['x']
    assert table.stop_reasons() == {'x': 'no fresh command for 3 periods'}
    tick = table.take()
    assert math.isnan(tick.efforts[0]) and tick.stopped == []


def test_newest_command_is_held_and_late_ticks_stop_the_axis_until_re_armed() -> None:
    table = CommandTable(['x'], brake_after=3)
    late_ticks_stop(table)
    # Commands return: the axis stays braked (said once), however many come.
    assert table.offer('x', 5 * T, -0.5, arrived_ns=5 * T + 3_000_000)
    tick = table.take()
    assert math.isnan(tick.efforts[0]) and tick.returned == ['x'] and tick.resumed == []
    assert table.offer('x', 6 * T, -0.4)
    tick = table.take()
    assert math.isnan(tick.efforts[0]) and tick.returned == []
    # The owner's brake request acknowledges the stop; its next valid command re-arms.
    assert table.offer('x', 7 * T, math.nan)
    assert math.isnan(table.take().efforts[0]) and table.stop_reasons()
    assert table.offer('x', 8 * T, 0.25)
    tick = table.take()
    assert tick.efforts == [0.25] and tick.resumed == ['x'] and table.stop_reasons() == {}
    assert table.late_fraction('x') == 4 / 9  # nine ticks since the first command, four late
    assert table.longest_late_run('x') == 4
    stats = table.latency_stats('x')
    assert stats['median'] == 0.0025 and stats['max'] == 0.003


def test_a_brake_request_before_the_stop_does_not_re_arm_it() -> None:
    table = CommandTable(['x'], brake_after=2)
    table.offer('x', 0, math.nan)  # a tripped controller, before the stream ended
    table.take()
    late_ticks = [table.take() for _ in range(2)]
    assert late_ticks[-1].stopped == ['x']
    table.offer('x', 3 * T, 1.0)
    assert math.isnan(table.take().efforts[0])  # still stopped: nothing acknowledged it


def test_the_operator_releases_a_stopped_axis_which_waits_for_a_fresh_command() -> None:
    table = CommandTable(['x'], brake_after=3)
    late_ticks_stop(table)
    assert table.release('x') and not table.release('x')
    assert math.isnan(table.take().efforts[0])  # released, but no fresh command yet
    table.offer('x', 9 * T, 2.0)
    tick = table.take()
    assert tick.efforts == [2.0] and tick.resumed == ['x']


def test_a_stop_from_outside_latches_with_its_reason_even_with_fresh_commands() -> None:
    table = CommandTable(['x', 'y'], brake_after=10)
    for k in range(2):
        table.offer('x', k * T, 1.0)
        table.offer('y', k * T, 2.0)
        assert table.take().efforts == [1.0, 2.0]
    assert table.stop('x', 'speed 900 mm/s above the limit') and not table.stop('x', 'again')
    table.offer('x', 2 * T, 1.0)
    table.offer('y', 2 * T, 2.0)
    tick = table.take()
    assert math.isnan(tick.efforts[0]) and tick.efforts[1] == 2.0  # only x
    assert table.stop_reasons() == {'x': 'speed 900 mm/s above the limit'}


def test_an_older_command_than_the_one_held_is_dropped() -> None:
    table = CommandTable(['x'], brake_after=10)
    assert table.offer('x', 2 * T, 1.0)
    assert not table.offer('x', T, 9.0)  # answers an older state: arrived out of order
    assert not table.offer('x', 2 * T, 9.0)  # the same state again
    assert table.take().efforts == [1.0]


def test_lockstep_step_is_complete_when_every_axis_answered_it() -> None:
    table = CommandTable(['x', 'y', 'z'], brake_after=10)
    table.offer('x', T, 1.0)
    table.offer('z', T, 3.0)
    assert not table.complete(T) and table.missing(T) == ['y']
    table.offer('y', T, 2.0)
    assert table.complete(T) and table.values() == [1.0, 2.0, 3.0]
