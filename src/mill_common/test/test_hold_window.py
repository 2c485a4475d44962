import math

import pytest
from mill_common.hold_window import (
    HoldWindow,
    StallWatch,
    drive_word,
    effort_said,
    hold_time,
    said_at,
    state_gap,
)
from mill_common.parameters import ParameterError

MS = 1_000_000
T = 1 * MS  # 1 kHz


def test_window_is_max_hold_at_rest_and_shrinks_with_speed():
    w = HoldWindow()
    assert w.hold_time(0.0) == w.max_hold == 0.5
    assert w.hold_time(float('nan')) == w.max_hold
    # (1 mm - 0.5 mm) / 16 mm/s: the commissioning job's top speed
    assert w.hold_time(0.016) == pytest.approx(0.03125)
    assert w.hold_time(-0.016) == w.hold_time(0.016)
    # slow enough that the room lasts longer than max_hold: max_hold
    assert w.hold_time(1e-4) == 0.5


@pytest.mark.parametrize('v', [1e-5, 1e-3, 0.016, 0.1, 0.5, -0.3])
def test_blind_run_stays_within_the_excursion(v):
    w = HoldWindow(excursion=0.002, hold_deviation=0.0005)
    assert abs(v) * w.hold_time(v) + w.hold_deviation <= w.excursion + 1e-15


def test_excursion_must_leave_room_beyond_the_hold_deviation():
    with pytest.raises(ParameterError, match='excursion'):
        HoldWindow(excursion=0.0005, hold_deviation=0.0005)
    assert hold_time(0.1, 0.0005, 0.001, 0.5) == 0.0  # no room: the first late tick stops


def test_stall_watch_measures_late_wakes_on_the_monotonic_clock():
    watch = StallWatch(T, 10 * MS)
    assert watch.wake(0) is None
    assert watch.wake(1 * MS) is None
    assert watch.wake(12 * MS) is None  # 10 ms late: not more than the threshold
    stall = watch.wake(125 * MS, wall_ns=7)
    assert stall is not None and stall.length_ns == 112 * MS and stall.due_ns == 13 * MS
    assert stall.describe('drive plant (pid 9)') == 'drive plant (pid 9) stalled 112 ms (monotonic)'
    assert watch.count == 1 and watch.longest == stall
    assert watch.within(0, 126 * MS) == 112 * MS
    assert watch.within(100 * MS, 126 * MS) == 25 * MS
    assert watch.within(125 * MS, 126 * MS) == 0


def test_a_stall_in_progress_counts_before_its_late_wake_is_seen():
    """A callback that runs before the watch's own late wake (the same executor woke from a
    stall): the overdue time of the watch is the process's stall."""
    watch = StallWatch(20 * MS, 10 * MS)
    watch.wake(0)
    assert watch.within(0, 25 * MS) == 0  # 5 ms overdue: within the threshold
    assert watch.within(0, 80 * MS) == 60 * MS  # due at 20 ms, not woken by 80 ms
    assert watch.within(50 * MS, 80 * MS) == 30 * MS


def test_a_gap_shorter_than_the_window_is_reported_not_tripped():
    w = HoldWindow()
    # the drive froze 15 ms: the controller saw no state for 18 ms, it was awake itself
    got = state_gap(18 * MS, T, 0.0, w, drive_stopped=False, own_stall_ns=0, mono_ns=18 * MS)
    assert not got.trip
    assert '18.0 ms' in got.report and 'the states stopped arriving' in got.report
    # the old contract (no word from the driver): as long as it is shorter than the window
    got = state_gap(18 * MS, T, 0.0, w, drive_stopped=None)
    assert not got.trip and got.report
    # the controller's own process slept
    got = state_gap(120 * MS, T, 0.0, w, drive_stopped=False, own_stall_ns=115 * MS)
    assert not got.trip and "this controller's own process stalled 115 ms" in got.report
    # jitter: no report
    assert state_gap(3 * MS, T, 0.0, w, drive_stopped=False) == state_gap(0, T, 0.0, w, False)
    assert not state_gap(3 * MS, T, 0.0, w, drive_stopped=False).report


def test_only_the_drive_says_it_stopped_the_axis():
    w = HoldWindow()
    # a long gap from a drive that says it did not stop the axis: a report, never a trip
    got = state_gap(2_000 * MS, T, 0.016, w, drive_stopped=False)
    assert not got.trip and got.report
    # the drive's word trips, whatever the gap
    got = state_gap(T, T, 0.0, w, drive_stopped=True)
    assert 'the drive says it has stopped the axis' in got.trip


def test_a_driver_that_does_not_say_is_judged_by_the_window():
    w = HoldWindow()
    assert w.hold_time(0.016) == pytest.approx(0.03125)
    got = state_gap(32 * MS, T, 0.016, w, drive_stopped=None)
    assert "beyond the drive's window of 31.2 ms at 16.0 mm/s" in got.trip
    assert not state_gap(31 * MS, T, 0.016, w, drive_stopped=None).trip
    assert not state_gap(500 * MS, T, 0.0, w, drive_stopped=None).trip  # at rest: 0.5 s
    assert state_gap(501 * MS, T, 0.0, w, drive_stopped=None).trip
    # A period is no gap, however fast the axis (the drive stops it at the first late tick).
    assert not state_gap(T, T, 2.0, w, drive_stopped=None).trip
    assert state_gap(2 * T, T, 2.0, w, drive_stopped=None).trip


def test_the_effort_a_drive_says_reads_back_as_its_word() -> None:
    assert math.isnan(effort_said(True, 0.3)) and drive_word([effort_said(True, 0.3)]) is True
    assert effort_said(False, 0.3) == 0.3 and drive_word([0.3]) is False
    assert effort_said(False, math.nan) == 0.0  # braked before its first command: not stopped
    assert drive_word([]) is None  # a driver of the old contract says nothing


def test_said_at_takes_the_steps_word_and_forgets_the_states_before_it() -> None:
    said: dict[int, bool | None] = {1: True, 2: None, 3: False, 5: True}
    assert said_at(said, 3) is False
    assert said == {5: True}  # 1 and 2 were dropped by the timing
    assert said_at(said, 4) is None and said == {5: True}  # a step whose state said nothing
