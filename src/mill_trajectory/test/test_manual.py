"""Manual commands between jobs (mill_trajectory.manual): what moves, within which limits,
and why a command is refused."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mill_trajectory.base import TrajectorySample
from mill_trajectory.gcode import Setup
from mill_trajectory.gcode_program import DEFAULT_TOLERANCE
from mill_trajectory.manual import Machine, Manual
from mill_trajectory.planner import Limits
from mill_trajectory.program import ProgramParams, ProgramTrajectory
from mill_trajectory.toolpath import Travel

T = 1e-3
VMAX, AMAX, JMAX = 0.05, 0.5, 10.0  # the machine's limits per axis (gcode.max_* defaults)
START = (0.01, 0.0, 0.0)  # where the job ends


def _machine(home: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> Machine:
    limits = Limits((VMAX,) * 3, (AMAX,) * 3, (JMAX,) * 3, DEFAULT_TOLERANCE)  # type: ignore[arg-type]
    travel = Travel((-0.1, -0.1, -0.05), (0.1, 0.1, 0.05))
    return Machine(limits, travel, T, 0.005, Setup(home=home))


def _manual(realtime: bool = True) -> Manual:
    """A session whose job (a dwell at START, 0.5 s) has started at t = 0."""
    job = ProgramTrajectory(ProgramParams(start=list(START), segments=['dwell 0.5']))
    manual = Manual(_machine(), realtime)
    manual.job_started(job, job.end_time)
    return manual


def _run(manual: Manual, t: float, until: float = 60.0) -> tuple[list[TrajectorySample], float]:
    """The reference on the grid from t until the move under way has come to rest."""
    assert manual.path is not None
    out = []
    k = round(t / T)
    while manual.busy(k * T) is not None:
        out.append(manual.path.sample(k * T))
        k += 1
        assert k * T < until, 'the move never came to rest'
    out.append(manual.path.sample(k * T))
    return out, k * T


def _within_limits(samples: list[TrajectorySample]) -> None:
    v = np.array([s.velocity for s in samples])
    a = np.array([s.acceleration for s in samples])
    assert np.abs(v).max() <= VMAX * (1 + 1e-9)
    assert np.abs(a).max() <= AMAX * (1 + 1e-9)
    assert np.abs(np.diff(a, axis=0) / T).max() <= JMAX * 1.01
    assert np.abs(np.diff(v, axis=0) / T).max() <= AMAX * 1.01


def test_a_jog_by_increment_moves_one_axis_by_that_distance_within_the_limits() -> None:
    manual = _manual()
    order = manual.jog('x', 0.002, 0.6)
    assert order.accepted, order.message
    got, _ = _run(manual, 0.6)
    p = np.array([s.position for s in got])
    assert p[-1] == pytest.approx((0.012, 0.0, 0.0), abs=1e-12)
    assert np.abs(p[:, 1:]).max() == 0.0  # y and z stand still
    v = np.array([s.velocity for s in got])
    assert np.abs(v[:, 0]).max() == pytest.approx(0.005, rel=1e-6)  # jog.speed
    _within_limits(got)
    # From rest where the job stood, the first sample after the command.
    assert got[0].position == START and got[0].velocity == (0.0, 0.0, 0.0)


def test_a_continuous_jog_runs_until_stopped_and_comes_to_rest_within_the_limits() -> None:
    manual = _manual()
    order = manual.jog_continuous('y', -0.02, 0.6)
    assert order.accepted, order.message
    assert manual.path is not None
    got = [manual.path.sample(k * T) for k in range(600, 1200)]  # 0.6 s at up to 20 mm/s
    assert got[-1].velocity[1] == pytest.approx(-0.02, rel=1e-9)
    assert manual.jog('x', 0.001, 1.2).message.startswith('continuous jog of y at -20.000 mm/s')
    stop = manual.jog_stop(1.2)
    assert stop.accepted, stop.message
    assert not manual.jog_stop(1.2).accepted  # stopping already
    rest, t = _run(manual, 1.2)
    got += rest
    _within_limits(got)
    y = rest[-1].position[1]
    assert -0.1 < y < got[-len(rest)].position[1]  # stopped on the way, short of travel.min
    assert rest[-1].velocity == (0.0, 0.0, 0.0)
    assert manual.busy(t) is None
    assert not manual.jog_stop(t).accepted  # nothing under way


def test_a_continuous_jog_not_stopped_ends_at_the_travel_limit() -> None:
    manual = _manual()
    assert manual.jog_continuous('z', 0.05, 0.6).accepted
    got, t = _run(manual, 0.6)
    assert got[-1].position[2] == pytest.approx(0.05, abs=1e-12)  # travel.max of z
    _within_limits(got)
    refused = manual.jog_continuous('z', 0.01, t)
    assert not refused.accepted and refused.message == 'z stands at travel.max 0.05 m already'


def test_home_goes_to_the_home_position_and_set_home_moves_it() -> None:
    manual = _manual()
    assert manual.go_home(0.6).accepted
    got, t = _run(manual, 0.6)
    assert got[-1].position == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    _within_limits(got)
    assert manual.jog('z', -0.003, t).accepted
    _, t = _run(manual, t)
    order = manual.set_home(t)
    assert order.accepted and order.message == 'home set to (0.000, 0.000, -3.000) mm'
    assert manual.jog('x', 0.004, t).accepted
    _, t = _run(manual, t)
    assert manual.go_home(t).accepted
    got, _ = _run(manual, t)
    assert got[-1].position == pytest.approx((0.0, 0.0, -0.003), abs=1e-12)


def test_an_mdi_line_is_read_planned_and_run_from_where_the_machine_stands() -> None:
    manual = _manual()
    order = manual.mdi('G91 G1 X-4 Y3 F600', 0.6)  # relative, 10 mm/s
    assert order.accepted, order.message
    got, t = _run(manual, 0.6)
    assert got[-1].position == pytest.approx((0.006, 0.003, 0.0), abs=1e-12)
    speed = np.linalg.norm(np.array([s.velocity for s in got]), axis=1)
    assert speed.max() == pytest.approx(0.01, rel=1e-6)
    _within_limits(got)
    # G28 goes to the session's home, as ~/home does.
    assert manual.set_home(t).accepted
    assert manual.mdi('G0 X0 Y0', t).accepted
    _, t = _run(manual, t)
    assert manual.mdi('G28', t).accepted
    got, _ = _run(manual, t)
    assert got[-1].position == pytest.approx((0.006, 0.003, 0.0), abs=1e-12)


@pytest.mark.parametrize(
    ('line', 'message'),
    [
        ('G1 X1 Y', 'mdi:1:7: '),
        ('G1 X1', 'mdi:1:1: '),  # no feed
        ('G0 X200', 'mdi:1:1: move outside the machine travel: x = 0.2 m is above travel.max'),
        ('M0', 'mdi:1:1: a pause (M0, M1) in MDI has nothing to pause'),
        ('M3 S1000', 'mdi:1:'),
        ('G0 X1\nG0 X2', 'MDI runs one line'),
        ('  ', 'MDI needs a G-code line'),
    ],
)
def test_an_mdi_line_that_cannot_run_is_refused_with_where_and_why(line: str, message: str) -> None:
    manual = _manual()
    order = manual.mdi(line, 0.6)
    assert not order.accepted
    assert order.message.startswith(message), order.message
    assert '\n' not in order.message
    assert manual.motion is None  # nothing moves


def test_refusals_say_why_in_one_line() -> None:
    manual = _manual()
    running = manual.jog('x', 0.001, 0.25)
    assert not running.accepted
    assert running.message == 'a job is running (t = 0.25 s of 0.50 s): wait for its end'
    assert manual.jog('q', 0.001, 0.6).message == "unknown axis 'q': one of x, y, z"
    assert not manual.jog('x', math.nan, 0.6).accepted
    assert not manual.jog('x', 0.0, 0.6).accepted
    beyond = manual.jog('x', 0.095, 0.6)
    assert not beyond.accepted
    assert beyond.message == (
        'jog x +95.000 mm would leave the machine travel: x = 0.105 m is above travel.max 0.1 m'
    )
    fast = manual.jog_continuous('x', 0.06, 0.6)
    assert fast.message == '60 mm/s is above the velocity limit of x, gcode.max_velocity 50 mm/s'
    assert manual.jog('x', 0.001, None).message.startswith('the job has not started yet')
    lockstep = _manual(realtime=False)
    assert lockstep.go_home(0.6).message.startswith('timing lockstep replays a job')
    assert not lockstep.set_home(0.6).accepted
    # A move under way: nothing else moves, and the move says what it is.
    assert manual.jog('x', 0.001, 0.6).accepted
    busy = manual.mdi('G0 X0', 0.6)
    assert busy.message == 'jog x +1.000 mm is under way: wait for its end or call ~/jog_stop'
    for order in (running, beyond, fast, busy):
        assert '\n' not in order.message


def test_a_stop_from_the_axis_speed_limit_is_prompt_and_within_the_limits() -> None:
    manual = _manual()
    assert manual.jog_continuous('x', -VMAX, 0.6).accepted
    assert manual.path is not None
    got = [manual.path.sample(k * T) for k in range(600, 1600)]
    assert got[-1].velocity[0] == pytest.approx(-VMAX, rel=1e-9)
    assert manual.jog_stop(1.6).accepted
    rest, t = _run(manual, 1.6)
    _within_limits(got + rest)
    # At least v/a + a/j = 0.15 s and 3.75 mm with the whole limits; a quarter is left out.
    assert t - 1.6 <= 0.25
    assert got[-1].position[0] - rest[-1].position[0] <= 0.006
