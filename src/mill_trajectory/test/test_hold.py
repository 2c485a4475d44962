"""M0/M1 pauses, feed hold and resume, and the program's messages in time (ROS-free cores)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from mill_common.parameters import validate
from mill_trajectory.config import build_job, build_schedule, parameter_specs
from mill_trajectory.feed_override import FeedOverride
from mill_trajectory.gcode import read_program
from mill_trajectory.gcode_program import GcodeTrajectory
from mill_trajectory.gcode_words import GcodeError
from mill_trajectory.hold import MESSAGE, PAUSE, TOOL_CHANGE, EventClock
from mill_trajectory.schedule import ClockedReference, JobProgress

DT = 1_000_000  # 1 ms
PROGRAM = """#<depth>=-2.5 #1=3
G21 G90 G17
(MSG, first cut)
G1 X10 F600
(DEBUG, depth #<depth> at #1)
M0
G1 Y10
(PRINT, done)
M30
"""


def _values(file: Path, **given: object) -> dict:
    specs = dict(parameter_specs())
    values = {name: spec.default for name, spec in specs.items()}
    values.update({'trajectory': 'gcode', 'gcode.file': str(file), **given})
    return {name: validate(specs[name], value, name) for name, value in values.items()}


def _part(tmp_path: Path, text: str = PROGRAM) -> Path:
    part = tmp_path / 'part.ngc'
    part.write_text(text)
    return part


def _run(schedule: ClockedReference, progress: JobProgress, ticks: int, start: int = 0) -> list:
    """Ticks of 1 ms from sample `start`: the samples that went out, in order."""
    out = []
    for k in range(start, start + ticks):
        points = schedule.answer(k * DT)
        if points is not None:
            out += points.samples
        progress.update(schedule.job_time(k * DT))
    return out


def test_events_come_at_the_time_their_line_runs(tmp_path: Path) -> None:
    path = build_job(_values(_part(tmp_path))).trajectory
    assert isinstance(path, GcodeTrajectory)
    kinds = [(e.kind, e.channel, e.text) for e in path.events]
    assert kinds == [
        (MESSAGE, 'MSG', 'first cut'),
        (MESSAGE, 'DEBUG', 'depth -2.500000 at 3.000000'),
        (PAUSE, '', 'M0: program stop'),
        (MESSAGE, 'PRINT', 'done'),
    ]
    msg, debug, pause, done = path.events
    # Before the first move: where the sharp path begins it, half its start's transition in.
    assert msg.time == pytest.approx(0.5 * path.planned.transitions[1], rel=1e-12)
    assert msg.where == f'{tmp_path / "part.ngc"}:3:1'
    # The DEBUG before M0 shows when the tool has come to rest at X10, as the pause does.
    assert debug.time == pause.time
    at_rest = path.sample(pause.time)
    assert at_rest.velocity == (0.0, 0.0, 0.0) and at_rest.acceleration == (0.0, 0.0, 0.0)
    assert at_rest.position == pytest.approx((0.01, 0.0, 0.0), abs=1e-15)
    # 10 mm at 10 mm/s, and the corner's half-transitions: a little over 1 s.
    assert 1.0 < pause.time < 1.2
    # PRINT after the last move: the path's end.
    assert done.time == path.end_time
    clock = EventClock(path.events)
    assert clock.due(0.5) == [msg] and clock.due(pause.time) == [debug, pause]
    assert clock.due(path.end_time) == [done] and clock.due(1e9) == []


def test_an_unset_parameter_in_debug_is_refused_in_one_line(tmp_path: Path) -> None:
    part = tmp_path / 'bad.ngc'
    part.write_text('G1 X1 F100\n(DEBUG, #<nowhere>)\n')
    with pytest.raises(GcodeError, match=r'bad\.ngc:2:1: .*nowhere') as err:
        read_program(str(part), (0.0, 0.0, 0.0))
    assert '\n' not in str(err.value)


def test_m1_pauses_only_with_the_optional_stop_switch_on(tmp_path: Path) -> None:
    part = tmp_path / 'm1.ngc'
    part.write_text('G1 X1 F100\nM1\nG1 X2\nM6 T1\n')
    on = build_job(_values(part)).trajectory
    off = build_job(_values(part, **{'gcode.optional_stop': False})).trajectory
    assert [(e.kind, e.text) for e in on.events] == [
        (PAUSE, 'M1: optional stop'),
        (TOOL_CHANGE, 'tool change: put in T1'),
    ]
    assert [e.kind for e in off.events] == [TOOL_CHANGE]
    assert off.end_time < on.end_time  # M1 ignored: the two moves blend


def test_a_pause_holds_the_programmed_point_until_resumed(tmp_path: Path) -> None:
    values = _values(_part(tmp_path))
    schedule, progress = build_schedule(values, FeedOverride())
    assert isinstance(schedule, ClockedReference) and schedule.scaled is not None
    holds = schedule.scaled.holds
    assert holds is not None
    path = schedule.path
    pause = path.pauses[0]
    plain = [path.sample(k * 1e-3) for k in range(int(pause.time * 1e3) + 1)]
    got = _run(schedule, progress, 3000)  # 3 s: 1.1 s to the pause, then held
    # Up to the pause, sample for sample the path (τ advances by T each sample).
    first = len(plain)
    for k in range(first):
        assert got[k].position == pytest.approx(plain[k].position, abs=1e-12), k
    held = got[first:]
    assert len(held) > 1800
    assert all(s.position == path.sample(pause.time).position for s in held)
    assert all(s.velocity == (0.0, 0.0, 0.0) == s.acceleration for s in held)
    assert [n.kind for n in holds.drain()] == ['paused']
    assert holds.state == 'paused' and progress.done_at is None
    refused = holds.feed_hold()
    assert not refused.accepted and 'at rest already' in refused.message
    assert holds.resume().accepted
    again = holds.resume()
    assert not again.accepted and again.message == 'nothing to resume: no pause and no feed hold'
    rest = _run(schedule, progress, int((path.end_time + 1.0) * 1e3), 3020)
    moved = [s.position[1] for s in rest]
    assert moved[-1] == pytest.approx(0.01, abs=1e-12) and max(moved) <= 0.01 + 1e-12
    # The job ends where its path ends, the time paused later than planned.
    assert progress.done_at is not None
    assert progress.done_at - path.end_time == pytest.approx(3.020 - pause.time, abs=2e-3)


def test_resume_after_ends_a_pause_by_itself_after_its_samples(tmp_path: Path) -> None:
    values = _values(_part(tmp_path), **{'gcode.resume_after': 0.25})
    schedule, progress = build_schedule(values, FeedOverride())
    assert isinstance(schedule, ClockedReference) and schedule.scaled is not None
    holds = schedule.scaled.holds
    assert holds is not None and holds.resume_samples == 250
    path = schedule.path
    got = _run(schedule, progress, int((path.end_time + 0.5) * 1e3))
    here = path.sample(path.pauses[0].time).position
    still = [i for i, s in enumerate(got) if s.position == here]
    assert len(still) == 250  # exactly resume_after at rest
    assert [n.kind for n in holds.drain()] == ['paused', 'resumed']
    assert progress.done_at is not None
    assert progress.done_at == pytest.approx(path.end_time + 0.25, abs=1.5e-3)


def test_feed_hold_needs_the_override_room(tmp_path: Path) -> None:
    schedule, _ = build_schedule(_values(_part(tmp_path)), FeedOverride())
    assert isinstance(schedule, ClockedReference) and schedule.scaled is not None
    holds = schedule.scaled.holds
    assert holds is not None
    answer = holds.feed_hold()
    assert not answer.accepted and 'feed_override.enabled' in answer.message


def test_feed_hold_decelerates_along_the_path_within_the_limits(tmp_path: Path) -> None:
    part = tmp_path / 'line.ngc'
    part.write_text('G1 X40 Y30 F1800\nM30\n')  # 50 mm at 30 mm/s, along (0.8, 0.6)
    values = _values(part, **{'feed_override.enabled': True})
    override = FeedOverride(0.0, 1.5)
    schedule, progress = build_schedule(values, override)
    assert isinstance(schedule, ClockedReference) and schedule.scaled is not None
    holds = schedule.scaled.holds
    assert holds is not None
    got = _run(schedule, progress, 800)  # at F by now
    assert holds.feed_hold().accepted
    refused = holds.feed_hold()
    assert not refused.accepted and refused.message.startswith('the feed is held already')
    got += _run(schedule, progress, 2000, 800)
    assert holds.state == 'held'
    assert holds.resume().accepted
    got += _run(schedule, progress, 3000, 2800)
    p = np.array([s.position for s in got])
    v = np.array([s.velocity for s in got])
    a = np.array([s.acceleration for s in got])
    # On the path: every point on the line from the origin along (0.8, 0.6).
    assert np.abs(0.6 * p[:, 0] - 0.8 * p[:, 1]).max() < 1e-12
    # Held: at rest and still, somewhere short of the end.
    stopped = np.flatnonzero(np.linalg.norm(v, axis=1) == 0.0)
    during = stopped[(stopped > 800) & (stopped < 2800)]
    assert len(during) > 1000
    assert np.ptp(p[during], axis=0).max() == 0.0 and p[during[0], 0] < 0.039
    # Within the machine's limits (0.05 m/s, 0.5 m/s², 10 m/s³ per axis) all along, the
    # reference's own acceleration and its differences alike.
    assert np.abs(v).max() <= 0.05 and np.abs(a).max() <= 0.5 * (1 + 1e-9)
    jerk = np.diff(a, axis=0) / 1e-3
    assert np.abs(jerk).max() <= 10.0 * 1.01
    assert np.abs(np.diff(v, axis=0) / 1e-3).max() <= 0.5 * 1.01
    # It gets to the end after the resume, and the job ends there.
    assert p[-1] == pytest.approx((0.04, 0.03, 0.0), abs=1e-12)
    assert progress.done_at is not None and math.isfinite(progress.done_at)
