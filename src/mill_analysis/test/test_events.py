"""Typed events, parsed once from the values of the /diagnostics statuses they arrive in."""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest
from mill_analysis.events import (
    BRAKED,
    DRIVE_SILENT,
    FAULT,
    STOPPED,
    TRIP,
    Event,
    Status,
    events_of,
    first_stop,
    statuses_of,
)

S = 1_000_000_000
START = 1_700_000_000 * S  # a realtime job's start on the system clock


def drive(at: float, **values: object) -> Status:
    return Status(START + round(at * S), 'plant: realtime', 0, 'running', _str(values))


def _str(values: dict[str, object]) -> dict[str, str]:
    return {k.replace('__', '.'): str(v) for k, v in values.items()}


def test_a_controller_trip_is_read_from_its_values_not_its_message() -> None:
    values = {
        'axis': 'y',
        'following_error_limit_m': '0.002',
        'trip_time_s': repr(START / S + 1.25),
        'trip_error_m': '-0.0021',
    }
    # the prose says nothing a parser could match: only the values count
    status = Status(START + 2 * S, 'y_controller: following error', 2, '(prose)', values)
    (event,) = events_of([status, status], START)  # told twice: one event
    assert event == Event('y', TRIP, event.time, event.detail, 'y_controller')
    assert event.time == pytest.approx(1.25, abs=1e-6)
    assert event.detail == 'following error |e| = 2.100 mm > 2 mm: braked'
    assert event.text().startswith('y axis: trip at t = 1.2500 s (y_controller): following error')
    # running: no trip
    running = Status(START, 'y_controller: following error', 0, 'axis y: running', {'axis': 'y'})
    assert events_of([running], START) == []


def test_a_trip_status_without_its_axis_takes_the_axis_of_its_node() -> None:
    values = {'following_error_limit_m': '0.002', 'trip_time_s': '3.5', 'trip_error_m': '0.003'}
    status = Status(4 * S, 'x_controller: following error', 2, '', values)
    (event,) = events_of([status], axis_of={'x_controller': 'x'})
    assert (event.axis, event.kind, event.time) == ('x', TRIP, 3.5)


def test_the_drive_counts_give_one_event_per_new_stop_brake_and_fault() -> None:
    statuses = [
        drive(0.5, x__stops=0, x__stopped='', x__invalid_commands=0),
        drive(1.0, x__stops=1, x__stopped='no fresh command', x__invalid_commands=0),
        drive(2.0, x__stops=1, x__stopped='no fresh command', x__invalid_commands=3),
        drive(3.0, x__stops=1, x__stopped='', x__invalid_commands=7, x__fault='overtravel'),
        drive(3.5, x__stops=3, x__stopped='speed limit', x__fault='overtravel'),
        # brake requests again after a status where their count stood still: still the
        # axis's one `braked` (a status cannot tell one series of them from the next)
        drive(4.0, x__stops=3, x__invalid_commands=7),
        drive(4.5, x__stops=3, x__invalid_commands=9),
    ]
    got = [(e.axis, e.kind, round(e.time, 6), e.detail) for e in events_of(statuses, START)]
    assert got == [
        ('x', STOPPED, 1.0, 'no fresh command'),
        ('x', BRAKED, 2.0, 'brake request (invalid command)'),
        ('x', FAULT, 3.0, 'overtravel'),
        ('x', STOPPED, 3.5, 'speed limit'),  # two stops since the last status: both counted
        ('x', STOPPED, 3.5, 'speed limit'),
    ]
    assert first_stop(events_of(statuses, START), 'x') == pytest.approx(1.0)
    assert first_stop(events_of(statuses, START), 'y') is None


def test_statuses_of_diagnostic_arrays_keep_their_machine_only() -> None:
    def status(name: str, hw: str, level: bytes) -> SimpleNamespace:
        kv = SimpleNamespace(key='x.stops', value='1')
        return SimpleNamespace(name=name, hardware_id=hw, level=level, message='m', values=[kv])

    array = SimpleNamespace(
        header=SimpleNamespace(stamp=SimpleNamespace(sec=2, nanosec=5)),
        status=[status('plant: realtime', '/', b'\x02'), status('plant: realtime', '/m2', b'\x00')],
    )
    (only,) = statuses_of([array], '/')
    assert only == Status(2 * S + 5, 'plant: realtime', 2, 'm', {'x.stops': '1'})
    assert len(statuses_of([array])) == 2


def test_an_event_is_one_of_the_kinds_and_reads_back_from_json() -> None:
    with pytest.raises(ValueError, match='no kind of event'):
        Event('x', 'tripped', 1.0)
    silent = Event('', DRIVE_SILENT, math.nan, 'nothing on mill/x/state for 3.2 s')
    assert silent.to_json()['time'] is None
    assert Event.from_json(silent.to_json()) == silent or math.isnan(
        Event.from_json(silent.to_json()).time
    )
    trip = Event('z', TRIP, 0.5, 'd', 'z_controller')
    assert Event.from_json(trip.to_json()) == trip
    assert silent.text() == 'drive silent: nothing on mill/x/state for 3.2 s'


def test_a_foreign_publisher_is_told_once_per_drive_by_its_status_part() -> None:
    values = {'foreign_messages': '4'}
    seen = Status(START, 'plant: ownership', 2, 'foreign publishers ignored: ...', values)
    (event,) = events_of([seen, seen], START)
    assert (event.axis, event.kind, event.source) == ('', 'foreign_publisher', 'plant')


def test_program_messages_and_pauses_are_read_from_the_job_status_values() -> None:
    from mill_analysis.events import PAUSE, PROGRAM_MESSAGE, program_events_of

    def job(message: str, **values: object) -> Status:
        return Status(START, 'trajectory: job', 0, message, _str({'state': 'running', **values}))

    said = 'part.ngc:2:1: MSG: first cut'
    statuses = [
        job('job running', time=0.5),  # a periodic report: no event
        job(said, event='message', event_where='part.ngc:2:1', event_time_s=0.04),
        job(said, event='message', event_where='part.ngc:2:1', event_time_s=0.04),  # again
        job(
            'paused at part.ngc:4:1: M0',
            event='paused',
            event_where='part.ngc:4:1',
            event_time_s=1.1,
        ),
        Status(START, 'plant: realtime', 0, 'x', {'event': 'paused'}),  # not the job's
    ]
    events = program_events_of(statuses)
    assert [(e.kind, e.time, e.detail) for e in events] == [
        (PROGRAM_MESSAGE, 0.04, said),
        (PAUSE, 1.1, 'paused at part.ngc:4:1: M0'),
    ]
    assert events_of(statuses) == []  # not among the machine's events
