"""The drive's command table: zero-order hold, late periods, brake after N, release."""

from __future__ import annotations

import math

from mill_plant.command_table import CommandTable

T = 10_000_000  # [ns]


def test_before_the_first_command_an_axis_is_braked_and_not_counted_late() -> None:
    table = CommandTable(['x', 'y'], brake_after=3)
    for _ in range(5):
        tick = table.take()
        assert all(math.isnan(e) for e in tick.efforts)
        assert tick.newly_braked == [] and tick.resumed == []
    assert math.isnan(table.late_fraction('x'))  # no tick counted before the job started


def test_newest_command_is_held_and_late_ticks_brake_after_n_then_release() -> None:
    table = CommandTable(['x'], brake_after=3)
    assert table.offer('x', 0, 1.5, arrived_ns=2_000_000)
    tick = table.take()
    assert tick.efforts == [1.5] and tick.resumed == ['x']  # released by its first command
    # Two ticks without a fresh command: the last one is held (zero-order hold).
    assert table.take().efforts == [1.5]
    assert table.take().efforts == [1.5]
    # The third late tick in a row brakes, once.
    tick = table.take()
    assert math.isnan(tick.efforts[0]) and tick.newly_braked == ['x']
    tick = table.take()
    assert math.isnan(tick.efforts[0]) and tick.newly_braked == []
    # A fresh command releases the axis with its value.
    assert table.offer('x', 5 * T, -0.5, arrived_ns=5 * T + 3_000_000)
    tick = table.take()
    assert tick.efforts == [-0.5] and tick.resumed == ['x']
    assert table.late_fraction('x') == 4 / 6  # six ticks since the first command, four late
    assert table.longest_late_run('x') == 4
    stats = table.latency_stats('x')
    assert stats['median'] == 0.0025 and stats['max'] == 0.003


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
