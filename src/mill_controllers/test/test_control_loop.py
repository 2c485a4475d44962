"""The controller's sample step (AxisControlLoop) and its input join (SampleJoin)."""

from __future__ import annotations

import math

import pytest
from mill_common.hold_window import HoldWindow
from mill_common.reference_buffer import ReferenceBuffer
from mill_common.signals import AxisReference, Estimate
from mill_common.timing import Lockstep, Realtime
from mill_controllers.control_loop import AxisControlLoop
from mill_controllers.registry import make_controller
from mill_controllers.sample_join import SampleJoin

B, T, DT = 20.96, 1e-3, 1_000_000
SLOTS = ('position', 'estimate')


def refs(*points: tuple[int, float]) -> ReferenceBuffer:
    buf = ReferenceBuffer()
    for ns, x in points:
        buf.add(ns, AxisReference(x, 0.0, 0.0))
    return buf


def loop(delay: int = 0, limit: float = 1e-3) -> AxisControlLoop:
    return AxisControlLoop(make_controller('pd', B, T, {}), T, limit, delay)


def test_the_step_is_the_law_on_the_inputs_of_the_sample() -> None:
    law = make_controller('pd', B, T, {})
    est = Estimate(0.0, 0.0, 0.0)
    cmd = loop().step(5 * DT, 0.0, est, refs((5 * DT, 1e-4)))
    from mill_common.signals import ControlInputs

    assert cmd.effort == law.compute(ControlInputs(0.005, 0.0, AxisReference(1e-4, 0, 0), est))
    assert not cmd.problem and not cmd.tripped


def test_with_delay_the_law_aims_at_the_predicted_state_and_the_reference_there() -> None:
    law = make_controller('pd', B, T, {})
    est = Estimate(2e-5, 0.0, 0.0)  # the observer's prediction for the period it acts in
    buf = refs((5 * DT, 0.0), (6 * DT, 1e-4))
    from mill_common.signals import ControlInputs

    cmd = loop(delay=1).step(5 * DT, 0.0, est, buf)
    aimed = ControlInputs(0.006, 2e-5, AxisReference(1e-4, 0.0, 0.0), est)
    assert cmd.effort == law.compute(aimed)


def test_the_trip_uses_the_error_at_the_states_own_stamp_and_latches() -> None:
    lp = loop(delay=1, limit=1e-3)
    est = Estimate(0.0, 0.0, 0.0)
    # 2 mm ahead at the aimed stamp but 0.5 mm at its own: no trip
    ok = lp.step(5 * DT, 0.0, est, refs((5 * DT, 5e-4), (6 * DT, 2e-3)))
    assert math.isfinite(ok.effort) and not ok.tripped
    bad = lp.step(6 * DT, 0.0, est, refs((6 * DT, 2e-3), (7 * DT, 2e-3)))
    assert bad.tripped and math.isnan(bad.effort)
    again = lp.step(7 * DT, 2e-3, est, refs((7 * DT, 2e-3), (8 * DT, 2e-3)))
    assert math.isnan(again.effort) and not again.tripped  # latched, reported once
    lp.set_limit(5e-3)  # a new limit (2 mm is within it) leaves the trip latched
    held = lp.step(8 * DT, 2e-3, est, refs((8 * DT, 0.0), (9 * DT, 0.0)))
    assert math.isnan(held.effort) and lp.trip.limit == 5e-3 and lp.trip.tripped
    assert lp.reset_trip() is not None
    back = lp.step(9 * DT, 2e-3, est, refs((9 * DT, 0.0), (10 * DT, 0.0)))
    assert math.isfinite(back.effort) and not back.tripped  # 2 mm < the new 5 mm


def test_a_drive_declared_stop_trips_with_its_reason_and_a_reset_re_arms_where_it_stands() -> None:
    from mill_common.signals import ControlInputs

    lp = AxisControlLoop(make_controller('pd', B, T, {}), T, 1e-3, window=HoldWindow())
    est = Estimate(0.0, 0.0, 0.0)

    def ramp(k: int) -> tuple[float, ReferenceBuffer]:  # a path at 100 mm/s, tracked
        return 0.1 * k * T, refs((k * DT, 0.1 * k * T))

    for k in (0, 1, 2, 3, 4):
        cmd = lp.step(k * DT, ramp(k)[0], est, ramp(k)[1], drive_stopped=False)
        assert not cmd.tripped and math.isfinite(cmd.effort), k
    stood = ramp(13)[0]  # the drive stopped the axis here, and says so in its next state
    reason = 'no fresh command for 4 ms of its ticks (the window at 100.0 mm/s: 5 ms)'
    stop = lp.step(23 * DT, stood, est, ramp(23)[1], drive_stopped=True, drive_reason=reason)
    assert stop.tripped and math.isnan(stop.effort)
    assert lp.trip.trip is not None
    assert (
        'the drive says it has stopped the axis (effort NaN in its state): ' + reason
    ) in lp.trip.trip.describe('x', 'at t = 0.023 s')
    # Reset: the reference is 1.1 mm away by now. The loop holds where the axis stands: a
    # small command, not the one that throws the axis at the reference. The drive still
    # says stopped until the re-arm reaches it: that is no new stop.
    assert lp.reset_trip() is not None and lp.hold == stood
    held = lp.step(24 * DT, stood, est, ramp(24)[1], drive_stopped=True)
    law = make_controller('pd', B, T, {})
    thrown = law.compute(ControlInputs(0.024, stood, AxisReference(ramp(24)[0], 0, 0), est))
    assert not held.tripped and abs(held.effort) < 0.01 * abs(thrown)
    # A reference that comes within half the limit of the held position is taken up again.
    cmd = lp.step(25 * DT, stood, est, refs((25 * DT, stood + 0.4e-3)), drive_stopped=False)
    assert lp.hold is None and not cmd.tripped and cmd.effort > 0.1 * thrown
    # A new stop, once the drive had released the axis: a trip again.
    again = lp.step(26 * DT, stood, est, refs((26 * DT, stood)), drive_stopped=True)
    assert again.tripped


def test_a_gap_shorter_than_the_window_is_reported_not_tripped() -> None:
    """The drive froze 15 ms: no state for 18 ms. It did not stop the axis (it says so), and
    the gap is reported with its length and whose stall it was, never as a stop."""
    lp = AxisControlLoop(make_controller('pd', B, T, {}), T, 1e-3, window=HoldWindow())
    est = Estimate(0.0, 0.0, 0.0)
    assert not lp.step(0, 0.0, est, refs((0, 0.0)), drive_stopped=False).gap
    cmd = lp.step(18 * DT, 0.0, est, refs((18 * DT, 0.0)), drive_stopped=False, mono_ns=18 * DT)
    assert not cmd.tripped and math.isfinite(cmd.effort)
    assert 'a gap of 18.0 ms' in cmd.gap and 'the states stopped arriving' in cmd.gap
    # Its own process slept: said so.
    cmd = lp.step(140 * DT, 0.0, est, refs((140 * DT, 0.0)), False, own_stall_ns=118 * DT)
    assert not cmd.tripped and "this controller's own process stalled 118 ms" in cmd.gap
    # Even a gap longer than any window: the drive did not say it stopped the axis.
    cmd = lp.step(1140 * DT, 0.0, est, refs((1140 * DT, 0.0)), drive_stopped=False)
    assert not cmd.tripped and cmd.gap


def test_a_driver_that_does_not_say_is_judged_by_the_window_at_the_estimated_speed() -> None:
    window = HoldWindow()
    v = 0.016  # (1 mm - 0.5 mm) / 16 mm/s = 31.25 ms
    est = Estimate(0.0, v, 0.0)
    lp = AxisControlLoop(make_controller('pd', B, T, {}), T, 1.0, window=window)
    lp.step(0, 0.0, est, refs((0, 0.0)))
    cmd = lp.step(31 * DT, 0.0, est, refs((31 * DT, 0.0)))  # shorter: a gap, reported
    assert not cmd.tripped and cmd.gap
    cmd = lp.step(63 * DT, 0.0, est, refs((63 * DT, 0.0)))  # 32 ms: beyond the window
    assert cmd.tripped and lp.trip.trip is not None
    assert "beyond the drive's window of 31.2 ms at 16.0 mm/s" in lp.trip.trip.cause
    # At rest the window is max_hold.
    lp = AxisControlLoop(make_controller('pd', B, T, {}), T, 1.0, window=window)
    rest = Estimate(0.0, 0.0, 0.0)
    lp.step(0, 0.0, rest, refs((0, 0.0)))
    assert not lp.step(499 * DT, 0.0, rest, refs((499 * DT, 0.0))).tripped
    assert lp.step(1000 * DT, 0.0, rest, refs((1000 * DT, 0.0))).tripped


def test_without_a_window_no_gap_trips() -> None:
    lp = loop()
    lp.step(0, 0.0, Estimate(0.0, 0.0, 0.0), refs((0, 0.0)))
    cmd = lp.step(10**9, 0.0, Estimate(0.0, 0.0, 0.0), refs((10**9, 0.0)), drive_stopped=True)
    assert not cmd.tripped and not cmd.gap


def test_a_following_error_trip_reset_goes_back_to_the_reference() -> None:
    lp = AxisControlLoop(make_controller('pd', B, T, {}), T, 1e-3, window=HoldWindow())
    est = Estimate(0.0, 0.0, 0.0)
    assert lp.step(0, 0.0, est, refs((0, 2e-3))).tripped
    lp.reset_trip()
    assert lp.hold is None  # the job's reference, as before


def test_a_law_that_cannot_compute_asks_for_the_brake_with_the_reason() -> None:
    lp = loop()
    cmd = lp.step(0, 0.0, Estimate(0.0, math.nan, 0.0), refs((0, 0.0)))
    assert math.isnan(cmd.effort) and cmd.problem


def test_a_law_of_another_output_unit_cannot_replace_the_running_one() -> None:
    lp = loop()
    with pytest.raises(ValueError, match='cascade_pi commands V'):
        lp.replace(make_controller('cascade_pi', B, T, {}))
    lp.replace(make_controller('gpi', B, T, {}))
    assert type(lp.law).PREFIX == 'gpi'


def test_a_refused_switch_names_the_law_running_after_earlier_switches() -> None:
    lp = loop()  # pd
    with pytest.raises(ValueError, match='the running pd commands N·m'):
        lp.replace(make_controller('machine_pi', B, T, {}))
    lp.replace(make_controller('adrc', B, T, {}))  # adrc's gains are pd.*, as pd's
    lp.step(0, 0.0, Estimate(0.0, 0.0, 0.0), refs((0, 0.0)))
    with pytest.raises(ValueError) as info:
        lp.replace(make_controller('cascade_pi', B, T, {}))
    assert str(info.value) == (
        'cascade_pi commands V but the running adrc commands N·m: '
        'the plant input cannot change unit mid-job'
    )


def test_lockstep_join_waits_for_every_input_and_the_reference_in_order() -> None:
    join = SampleJoin(Lockstep(DT), SLOTS, 0)
    join.offer('position', 0, 1.0)
    join.offer('position', DT, 2.0)
    join.offer('estimate', DT, 'e1')
    assert list(join.due()) == []  # sample 1 waits for the reference (and 0 was dropped)
    join.add_reference(DT, AxisReference(0, 0, 0))
    assert [ns for ns, _ in join.due()] == [DT]
    assert join.last_ns == DT


def test_realtime_join_steps_the_newest_and_drops_a_sample_beyond_the_reference() -> None:
    join = SampleJoin(Realtime(DT), SLOTS, DT)
    join.add_reference(0, AxisReference(0, 0, 0))
    join.add_reference(2 * DT, AxisReference(0, 0, 0))
    for ns in (0, DT):
        join.offer('position', ns, 0.0)
        join.offer('estimate', ns, 'e')
    assert [ns for ns, _ in join.due()] == [DT]  # the newest; it aims at 2 ms: there
    join.offer('position', 5 * DT, 0.0)
    join.offer('estimate', 5 * DT, 'e')
    assert list(join.due()) == [] and join.late_references == 1
