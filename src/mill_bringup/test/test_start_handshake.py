"""Between jobs: a drive that stays up (an --external clock node) may hold an axis stopped
from an earlier job. The job refuses to start on it, in one line naming the axis and the
stop's reason (exit code 2), unless the operator asked to re-arm (--rearm): the runner then
calls the drive's ~/release before any node of the job starts and checks its next status."""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Any

import pytest
from mill_analysis.events import REFUSED, Status
from mill_bringup.cli import set_timing
from mill_bringup.jobs.realtime import RealtimeAxisJob
from mill_bringup.jobs.registry import job_for
from mill_bringup.runner import start
from mill_bringup.runner.options import RunOptions, StartRefused

from mill_bringup import scenario

REASON = 'no fresh command for 500 ms of its ticks (the window at rest: 500 ms)'


class Drive:
    """What the monitor heard of the drive: its statuses, newest last."""

    def __init__(self, *values: dict[str, str]) -> None:
        self.heard = [Status(k, 'plant: realtime', 0, 'running', v) for k, v in enumerate(values)]
        self.spins = 0

    def status(self, name: str) -> dict[str, str] | None:
        for s in reversed(self.heard):
            if s.name == name:
                return dict(s.values)
        return None

    def statuses(self) -> list[Status]:
        return list(self.heard)


def realtime_job() -> RealtimeAxisJob:
    scen = scenario.load('slotting')
    set_timing(scen, 'realtime')
    job = job_for(scen)
    assert isinstance(job, RealtimeAxisJob)
    return job


def session_of(monitor: Drive, after_spin: dict[str, str] | None = None) -> Any:
    notes: list[str] = []

    def spin(when: str) -> None:
        monitor.spins += 1
        if after_spin is not None and monitor.spins == 1:
            monitor.heard.append(Status(99, 'plant: realtime', 0, 'running', after_spin))

    return SimpleNamespace(
        monitor=monitor,
        executor=None,
        progress=SimpleNamespace(note=notes.append),
        spin=spin,
        rearmed={},
        notes=notes,
    )


STOPPED_Y = {'x.stopped': '', 'y.stopped': REASON, 'z.stopped': '', 'y.stops': '1'}
FREE = {'x.stopped': '', 'y.stopped': '', 'z.stopped': ''}
EXTERNAL = RunOptions(external=frozenset({'plant'}))


def test_the_job_reads_the_latched_axes_from_the_drives_status() -> None:
    job = realtime_job()
    assert job.latched(Drive()) is None  # nothing heard yet
    assert job.latched(Drive(FREE)) == {}
    assert job.latched(Drive(STOPPED_Y)) == {'y': REASON}
    assert job.latched(Drive(STOPPED_Y, FREE)) == {}  # the newest status counts


def test_a_job_refuses_to_start_on_a_latched_axis_in_one_line() -> None:
    session = session_of(Drive(STOPPED_Y))
    with pytest.raises(StartRefused) as caught:
        start.handshake(session, realtime_job(), EXTERNAL)
    event = caught.value.event
    assert (event.axis, event.kind, event.source) == ('y', REFUSED, 'plant')
    assert math.isnan(event.time)
    line = str(caught.value)
    assert '\n' not in line
    assert line.startswith(f'axis y held stopped by the drive plant ({REASON}): job not started')
    assert line.endswith(
        "run again with --rearm (the runner then calls the drive's ~/release "
        'before any node of the job starts)'
    )
    assert session.rearmed == {}


def test_a_drive_the_runner_starts_itself_or_one_with_no_stopped_axis_starts_at_once() -> None:
    job = realtime_job()
    own = session_of(Drive(STOPPED_Y))
    start.handshake(own, job, RunOptions())  # not external: a fresh drive, not asked
    assert own.monitor.spins == 0
    free = session_of(Drive(FREE))
    start.handshake(free, job, EXTERNAL)
    assert free.monitor.spins == 0 and free.notes == []


def test_rearm_releases_the_latched_axis_through_the_drive_and_checks_its_next_status(
    monkeypatch,
) -> None:
    calls: list[str] = []

    def release(node: Any, executor: Any, target: str, wait: float) -> str:
        calls.append(target)
        return 'released y: braked until the next fresh command'

    monkeypatch.setattr(start, 'release', release)
    session = session_of(Drive(STOPPED_Y), after_spin=FREE)
    rearm = RunOptions(external=frozenset({'plant'}), rearm=True)
    start.handshake(session, realtime_job(), rearm)
    assert calls == ['plant']
    assert session.rearmed == {'y': REASON}
    assert session.notes == [
        '--rearm: plant/~release: released y: braked until the next fresh command'
    ]
    # the drive still says y is stopped after the release: refused all the same
    session = session_of(Drive(STOPPED_Y), after_spin=STOPPED_Y)
    with pytest.raises(StartRefused, match='still stopped after its ~/release: release it'):
        start.handshake(session, realtime_job(), rearm)
    # a drive without ~/release
    monkeypatch.setattr(start, 'release', lambda *a: None)
    session = session_of(Drive(STOPPED_Y))
    with pytest.raises(StartRefused, match=r'plant offers no ~/release: release it on the drive'):
        start.handshake(session, realtime_job(), rearm)


def test_a_drive_whose_status_is_named_otherwise_is_said_once() -> None:
    job = realtime_job()
    heard = [
        Status(1, 'plant: driver', 0, 'running', {'x.late': '0'}),
        Status(2, 'plant: driver', 0, 'running', {'x.late': '0'}),
        Status(3, 'trajectory: job', 0, 'running', {}),
    ]
    (warning,) = job.warnings(heard)
    assert warning.startswith(
        "the drive plant sent statuses named plant: driver but none named 'plant: realtime'"
    )
    assert job.warnings([*heard, Status(4, 'plant: realtime', 0, 'running', {})]) == []
    assert job.warnings(heard[2:]) == []  # a drive that said nothing: nothing to add
