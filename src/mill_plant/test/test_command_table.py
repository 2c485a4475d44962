"""The drive's command table: zero-order hold, late periods, a latched stop when the
controller's silence (over the drive's own ticks) would outlast the window H(v), release only
by the owner's re-arm (brake request, then a valid command) or the operator."""

from __future__ import annotations

import math

import pytest
from mill_common.hold_window import HoldWindow
from mill_plant.command_table import CommandTable, Tick
from mill_plant.motion_guard import MotionGuard

T = 10_000_000  # [ns]
MS = 1_000_000
# At rest, 35 ms: two late ticks of 10 ms are held, the third (30 ms + a period > 35) stops.
SHORT = HoldWindow(max_hold=0.035)


class Ticks:
    """A table ticked a period apart (or later: `skip` the drive's own stall)."""

    def __init__(self, table: CommandTable) -> None:
        self.table, self.ns = table, 0

    def __call__(self, skip: int = 0, speeds: dict[str, float] | None = None) -> Tick:
        self.ns += T + skip
        return self.table.take(self.ns, speeds)


def table_of(axes: list[str], window: HoldWindow = SHORT, period: int = T) -> CommandTable:
    return CommandTable(axes, window, period)


def test_before_the_first_command_an_axis_is_braked_and_not_counted_late() -> None:
    table = table_of(['x', 'y'])
    take = Ticks(table)
    for _ in range(5):
        tick = take()
        assert all(math.isnan(e) for e in tick.efforts)
        assert tick.stopped == [] and tick.resumed == []
    assert math.isnan(table.late_fraction('x'))  # no tick counted before the job started


def late_ticks_stop(table: CommandTable) -> Ticks:
    """x's first command, then ticks without one until the third late tick stops it."""
    take = Ticks(table)
    assert table.offer('x', 0, 1.5, arrived_ns=2_000_000)
    tick = take()
    assert tick.efforts == [1.5] and tick.resumed == ['x']  # released by its first command
    # Two ticks without a fresh command: the last one is held (zero-order hold).
    assert take().efforts == [1.5]
    assert take().efforts == [1.5]
    # The third late tick in a row stops the axis, once: one more period would exceed 35 ms.
    tick = take()
    assert math.isnan(tick.efforts[0]) and tick.stopped == ['x']
    assert table.stop_reasons() == {
        'x': 'no fresh command for 30 ms of its ticks (the window at rest: 35 ms)'
    }
    tick = take()
    assert math.isnan(tick.efforts[0]) and tick.stopped == []
    return take


def test_newest_command_is_held_and_late_ticks_stop_the_axis_until_re_armed() -> None:
    table = table_of(['x'])
    take = late_ticks_stop(table)
    # Commands return: the axis stays braked (said once), however many come.
    assert table.offer('x', 5 * T, -0.5, arrived_ns=5 * T + 3_000_000)
    tick = take()
    assert math.isnan(tick.efforts[0]) and tick.returned == ['x'] and tick.resumed == []
    assert table.offer('x', 6 * T, -0.4)
    tick = take()
    assert math.isnan(tick.efforts[0]) and tick.returned == []
    # The owner's brake request acknowledges the stop; its next valid command re-arms.
    assert table.offer('x', 7 * T, math.nan)
    assert math.isnan(take().efforts[0]) and table.stop_reasons()
    assert table.offer('x', 8 * T, 0.25)
    tick = take()
    assert tick.efforts == [0.25] and tick.resumed == ['x'] and table.stop_reasons() == {}
    assert table.late_fraction('x') == 4 / 9  # nine ticks since the first command, four late
    assert table.longest_late_run('x') == 4
    stats = table.latency_stats('x')
    assert stats['median'] == 0.0025 and stats['max'] == 0.003


def test_a_brake_request_before_the_stop_does_not_re_arm_it() -> None:
    table = table_of(['x'], HoldWindow(max_hold=0.025))  # the second late tick stops
    take = Ticks(table)
    table.offer('x', 0, math.nan)  # a tripped controller, before the stream ended
    take()
    late_ticks = [take() for _ in range(2)]
    assert late_ticks[-1].stopped == ['x']
    table.offer('x', 3 * T, 1.0)
    assert math.isnan(take().efforts[0])  # still stopped: nothing acknowledged it


def test_the_operator_releases_a_stopped_axis_which_waits_for_a_fresh_command() -> None:
    table = table_of(['x'])
    take = late_ticks_stop(table)
    assert table.release('x') and not table.release('x')
    assert math.isnan(take().efforts[0])  # released, but no fresh command yet
    table.offer('x', 9 * T, 2.0)
    tick = take()
    assert tick.efforts == [2.0] and tick.resumed == ['x']


def test_a_release_with_no_job_running_holds_braked_and_is_not_undone_by_the_window() -> None:
    """Between jobs nothing commands the axis: released, it waits braked as before its first
    command (no late tick, no new stop), however long; a command older than the one it held
    before the release is no fresh one."""
    table = table_of(['x'])
    take = late_ticks_stop(table)
    late = table.by_axis['x'].late
    assert table.release('x')
    for _ in range(100):  # 1 s: the window of 35 ms many times over
        tick = take()
        assert math.isnan(tick.efforts[0]) and tick.stopped == []
    assert table.stop_reasons() == {} and table.by_axis['x'].late == late
    assert not table.offer('x', 0, 3.0)  # answers a state from before the release
    assert math.isnan(take().efforts[0])
    table.offer('x', 200 * T, 2.0)  # the next job's first command arms it
    tick = take()
    assert tick.efforts == [2.0] and tick.resumed == ['x']
    assert [take().stopped for _ in range(3)][-1] == ['x']  # and the window watches again


def test_a_deactivated_drive_waits_for_fresh_commands_but_keeps_a_latched_stop() -> None:
    table = table_of(['x', 'y'])
    take = Ticks(table)
    table.offer('x', 0, 1.0)
    table.offer('y', 0, 2.0)
    take()
    table.stop('y', 'speed 900 mm/s above the limit')
    table.brake_all()  # deactivated at the end of a job
    for _ in range(10):  # no job: nothing counted, nothing stopped anew
        tick = take()
        assert all(math.isnan(e) for e in tick.efforts) and tick.stopped == []
    assert table.stop_reasons() == {'y': 'speed 900 mm/s above the limit'}
    table.offer('x', 20 * T, 1.5)
    table.offer('y', 20 * T, 2.5)
    tick = take()  # the next job: x resumes, y stays stopped until released
    assert tick.efforts[0] == 1.5 and math.isnan(tick.efforts[1]) and tick.returned == ['y']


def test_a_stop_from_outside_latches_with_its_reason_even_with_fresh_commands() -> None:
    table = table_of(['x', 'y'], HoldWindow())
    take = Ticks(table)
    for k in range(2):
        table.offer('x', k * T, 1.0)
        table.offer('y', k * T, 2.0)
        assert take().efforts == [1.0, 2.0]
    assert table.stop('x', 'speed 900 mm/s above the limit') and not table.stop('x', 'again')
    table.offer('x', 2 * T, 1.0)
    table.offer('y', 2 * T, 2.0)
    tick = take()
    assert math.isnan(tick.efforts[0]) and tick.efforts[1] == 2.0  # only x
    assert table.stop_reasons() == {'x': 'speed 900 mm/s above the limit'}


def test_an_older_command_than_the_one_held_is_dropped() -> None:
    table = table_of(['x'], HoldWindow())
    assert table.offer('x', 2 * T, 1.0)
    assert not table.offer('x', T, 9.0)  # answers an older state: arrived out of order
    assert not table.offer('x', 2 * T, 9.0)  # the same state again
    assert table.take(T).efforts == [1.0]


def test_lockstep_step_is_complete_when_every_axis_answered_it() -> None:
    table = table_of(['x', 'y', 'z'], HoldWindow())
    table.offer('x', T, 1.0)
    table.offer('z', T, 3.0)
    assert not table.complete(T) and table.missing(T) == ['y']
    table.offer('y', T, 2.0)
    assert table.complete(T) and table.values() == [1.0, 2.0, 3.0]


# -- the window H(v) and whose lateness counts --------------------------------------------------
KHZ = MS  # 1 kHz


class KhzTicks(Ticks):
    def __call__(self, skip: int = 0, speeds: dict[str, float] | None = None) -> Tick:
        self.ns += KHZ + skip
        return self.table.take(self.ns, speeds)


def test_a_drive_stall_of_300_ms_brakes_nothing() -> None:
    """The drive itself slept 300 ms: it published no state, so no answer is missing; the
    answer to its last state, still unread at its first tick after the stall, comes next."""
    table = CommandTable(['x'], HoldWindow(), KHZ)
    take = KhzTicks(table)
    for k in range(3):
        table.offer('x', k * KHZ, 1.0)
        assert take(speeds={'x': 0.016}).efforts == [1.0]
    tick = take(skip=300 * MS, speeds={'x': 0.016})  # at speed: its window is 31 ms
    assert tick.efforts == [1.0] and tick.stopped == [] and table.stop_reasons() == {}
    assert table.longest_wait('x') == pytest.approx(0.001)  # one period asked, not 300 ms
    table.offer('x', take.ns - KHZ, 1.1)
    assert take(speeds={'x': 0.016}).efforts == [1.1]


@pytest.mark.parametrize('v', [0.0, 0.002, 0.016, 0.1, -0.05])
def test_a_controller_silence_of_the_window_at_speed_v_brakes(v: float) -> None:
    window = HoldWindow()
    hold_ms = window.hold_time(v) * 1e3
    table = CommandTable(['x'], window, KHZ)
    take = KhzTicks(table)
    table.offer('x', 0, 1.0)
    take(speeds={'x': v})
    late = 0
    while True:
        tick = take(speeds={'x': v})
        late += 1
        if tick.stopped:
            break
        assert late + 1 <= hold_ms + 1e-9  # held only while one more period stays within H
    # Stopped at the tick from which holding one more period would exceed H(v): the axis
    # ran blind at most H(v) (it ran the last held period before this tick).
    assert late <= hold_ms < late + 1
    assert math.isnan(tick.efforts[0])
    if v == 0.0:
        assert hold_ms == 500.0  # at rest the window is max_hold


def test_held_with_the_motion_guard_an_axis_stays_within_the_excursion() -> None:
    """The bound, with the guard: the command stream ends at speed v; the held command keeps
    the axis at v (on course), the table stops it at H(v); it ran at most excursion."""
    window = HoldWindow(excursion=0.002, hold_deviation=0.0005)
    for v in (0.001, 0.016, 0.05, 0.3):
        guard = MotionGuard(['x'], speed_limit=0.5, hold_deviation=window.hold_deviation)
        table = CommandTable(['x'], window, KHZ)
        x, k, fresh_until = 0.0, 0, 5
        stopped_at = None
        while stopped_at is None:
            ns = k * KHZ
            if k <= fresh_until:
                table.offer('x', ns, 1.0)
            holding = {'x': not table.by_axis['x'].fresh}
            assert guard.check(ns, {'x': x}, holding) == {}
            tick = table.take(ns, {'x': guard.speed('x')})
            if tick.stopped:
                stopped_at = x
            x += v * KHZ * 1e-9  # the held command keeps its speed over the next period
            k += 1
        anchor = v * (fresh_until * KHZ) * 1e-9  # where its last fresh command found it
        assert abs(stopped_at - anchor) + window.hold_deviation <= window.excursion + 1e-12, v
        assert guard.speed('x') == pytest.approx(v)
