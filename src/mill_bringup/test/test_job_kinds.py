"""What each kind of job says of its runs: the kind of record its bag holds (for `report`)
and what goes before the paper's verdicts of a run."""

from __future__ import annotations

from collections.abc import Callable

import pytest
from mill_analysis.events import Status
from mill_analysis.record import RunRecord
from mill_bringup.cli import set_timing
from mill_bringup.jobs.base import Ending
from mill_bringup.jobs.registry import JOB_KINDS, job_for
from mill_bringup.runner.cli import paper_text

from mill_analysis import bag_meta, papers
from mill_bringup import scenario


def test_every_job_kind_names_its_kind_of_record() -> None:
    assert {kind.KIND: kind.RECORD.NAME for kind in JOB_KINDS} == {
        'axis': bag_meta.AXIS,
        'axis-realtime': bag_meta.AXIS_REALTIME,
        'force': bag_meta.FORCE,
    }


def test_only_a_realtime_run_notes_that_its_verdicts_are_no_reproduction(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(
        papers, 'report', lambda paper, recs, _params=None: f'{paper}: {sorted(recs)}'
    )
    lockstep = job_for(scenario.load('maharof').variant('pi'))
    scen = scenario.load('maharof').variant('pi')
    set_timing(scen, 'realtime')
    realtime = job_for(scen)
    assert not lockstep.PAPER_NOTE and realtime.PAPER_NOTE.startswith('note: a realtime run: ')
    assert paper_text('maharof', {'a': lockstep}, {'a': None}) == "maharof: ['a']"
    both = paper_text('maharof', {'a': lockstep, 'b': realtime, 'c': realtime}, {'a': None})
    assert both == f"{realtime.PAPER_NOTE}\nmaharof: ['a']"  # said once


class Source:
    """What a job reads of a running graph, made up: state stamps, statuses, problems, and
    when the newest message of a topic arrived."""

    def __init__(
        self, stamps: dict[str, int], statuses: dict | None = None, arrived: dict | None = None
    ) -> None:
        self.stamps = stamps
        self.statuses = statuses or {}
        self.arrived = arrived or {}
        self.heard: list[str] = []

    def latest_stamp_ns(self, topic: str) -> int:
        return self.stamps.get(topic, -1)

    def messages(self, topic: str) -> list[bytes]:
        return []

    def status(self, name: str) -> dict[str, str] | None:
        return self.statuses.get(name)

    def problems(self) -> list[str]:
        return list(self.heard)

    def arrival_ns(self, topic: str) -> list[int]:
        return [self.arrived[topic]] if topic in self.arrived else []


def _realtime_slotting():
    scen = scenario.load('slotting')
    set_timing(scen, 'realtime')
    scen.add_override('*.design_period=0.0')
    return job_for(scen)


def test_a_driver_on_the_other_clock_is_refused_in_one_line() -> None:
    wall = 1_767_000_000 * 10**9  # a system-clock stamp
    lockstep = job_for(scenario.load('slotting'))
    with pytest.raises(scenario.ScenarioError, match=r'system clock .* --timing realtime'):
        lockstep.check(Source({'mill/x/state': wall}))
    lockstep.check(Source({'mill/x/state': 5 * 10**9}))  # sim time: fine
    realtime = _realtime_slotting()
    with pytest.raises(scenario.ScenarioError, match=r'on sim time .* runs in realtime'):
        realtime.check(Source({'mill/x/state': 10**9}))


class Clock:
    """The runner's system clock, moved by hand."""

    def __init__(self) -> None:
        self.ns = 1_767_000_000 * 10**9

    def __call__(self) -> int:
        return self.ns


S = 10**9


def _silent_job(clock: Clock):
    job = _realtime_slotting()
    job.clock_ns = clock
    job.start_ns = clock.ns - 10 * S
    return job


def _until_silent(job, clock: Clock, every: int, arrived: Callable[[], dict[str, int]]) -> str:
    """Look every `every` ns, the states' arrivals as `arrived` says, until the job calls the
    drive silent: its message."""
    for _ in range(200):
        try:
            job.check(Source(arrived(), arrived=arrived()))
        except scenario.ScenarioError as exc:
            return str(exc)
        clock.ns += every
    raise AssertionError('the drive was never called silent')


def test_a_drive_gone_silent_ends_a_realtime_job() -> None:
    clock = Clock()
    job = _silent_job(clock)
    y_last = clock.ns
    # The runner looks every 50 ms; x and z keep coming, y stops: found after 3 s, not before.
    said = _until_silent(
        job,
        clock,
        S // 20,
        lambda: {'mill/x/state': clock.ns, 'mill/y/state': y_last, 'mill/z/state': clock.ns},
    )
    assert 'went silent: nothing on mill/y/state' in said
    assert 3 * S < clock.ns - y_last <= 3 * S + S // 10


def test_a_drive_not_heard_since_the_start_ends_a_realtime_job() -> None:
    clock = Clock()
    job = _silent_job(clock)
    job.start_ns = clock.ns
    said = _until_silent(job, clock, S // 20, dict)
    assert 'went silent: nothing on mill/x/state' in said
    assert 3 * S < clock.ns - job.start_ns <= 3 * S + S // 10


def test_a_runner_that_went_without_the_cpu_does_not_call_the_drive_silent() -> None:
    clock = Clock()
    job = _silent_job(clock)
    fresh = {f'mill/{a}/state': clock.ns for a in 'xyz'}
    job.check(Source(fresh, arrived=fresh))
    clock.ns += 4 * S  # the runner was stopped 4 s
    # the states it has not taken yet are no silence of the drive ...
    job.check(Source(fresh, arrived=fresh))
    # ... nor those queued meanwhile that it takes now, with old stamps
    arrived = {topic: clock.ns for topic in fresh}
    job.check(Source(fresh, arrived=arrived))


def test_a_drive_silent_while_the_runner_stalls_again_and_again_is_found() -> None:
    clock = Clock()
    job = _silent_job(clock)
    last = clock.ns
    # Stalls of 1.5 s with a look between them: each counts as 1 s of silence.
    said = _until_silent(job, clock, 3 * S // 2, lambda: {f'mill/{a}/state': last for a in 'xyz'})
    assert 'went silent: nothing on mill/x/state' in said
    assert clock.ns - last == 6 * S  # the fifth look: 4 × 1 s counted


def _trip(axis: str, at_s: float) -> Status:
    values = {
        'axis': axis,
        'following_error_limit_m': '0.002',
        'trip_time_s': repr(at_s),
        'trip_error_m': '0.0025',
    }
    return Status(round(at_s * S), f'{axis}_controller: following error', 2, '(prose)', values)


def _drive(at_s: float, **values: str) -> Status:
    named = {k.replace('__', '.'): v for k, v in values.items()}
    return Status(round(at_s * S), 'plant: realtime', 0, 'running', named)


def _failures(job, heard: list[Status]) -> list[tuple[str, str]]:
    """The failures of a run whose runner heard these statuses until the job ended (what
    collect puts in the record, and the summary fails)."""
    rec = RunRecord.empty(0, 0.001)
    rec.events = job.events(heard)
    return [(e.axis, e.kind) for e in job.summary(rec, 1.0, Ending(tuple(heard))).failures]


def test_a_realtime_trip_or_brake_while_the_job_ran_fails_it() -> None:
    job = _realtime_slotting()
    job.start_ns = 1_767_000_000 * S
    t0 = job.start_ns / S
    other = Status(job.start_ns, 'plant: realtime', 1, 'sample rate not held', {'overruns': '3'})
    trip = _trip('y', t0 + 2.0)
    brake = _drive(t0 + 2.5, z__invalid_commands='4', z__stops='0')
    done = {'trajectory: job': {'state': 'done', 'time': '4.0', 'end_time': '4.0'}}
    assert job.complete(Source({}, done))
    # Only the statuses heard until the job ended are the job's: the runner takes them once
    # then (what comes after, as the graph stops, is not the job's).
    assert _failures(job, [other, trip, brake]) == [('y', 'trip'), ('z', 'braked')]
    events = job.events([trip])
    assert events[0].time == pytest.approx(2.0, abs=1e-6)  # the job's time
    lockstep = job_for(scenario.load('slotting'))
    assert _failures(lockstep, [_trip('y', 2.0)]) == []  # a simulation's trip is its result


def test_a_stop_the_drive_counted_fails_the_job_when_its_report_was_lost() -> None:
    job = _realtime_slotting()
    job.start_ns = 0
    heard = [_drive(4.0, x__stops='0', y__stops='1', y__stopped='no fresh command')]
    assert _failures(job, heard) == [('y', 'stopped')]  # no report of the stop: the count
    (event,) = job.events(heard)
    assert event.text() == 'y axis: stopped at t = 4.0000 s (plant): no fresh command'


def test_every_axis_node_waits_for_the_runner_and_a_recorded_step_needs_every_topic() -> None:
    """The runner keeps the commands too (its record counts them), so a controller answers only
    once the plant, its observer and the runner hear it; the plant of a recorded run waits
    for every topic of a step, the commands included, from the first step on."""
    from mill_bringup.catalogue import CONTROLLER

    from mill_common import topics

    job = job_for(scenario.load('slotting'))
    job.prepare_graph(monitored=True, recorded=True)
    scen = job.scenario
    for node in scen.nodes:
        if node.kind.per_axis:
            wanted = 3 if node.kind.role == CONTROLLER else 2
            assert scen.parameters(node.name)['min_subscribers'] == wanted, node.name
    assert {topics.joint_command(a) for a in 'xyz'} <= set(job.monitor_topics())
    steps = job.bag_handshake()
    assert steps is not None
    stepped = [f(a) for a in 'xyz' for f in (topics.state, topics.estimate, topics.joint_command)]
    for topic in [*stepped, topics.CUTTING_FORCE, topics.GROUND_TRUTH]:
        assert steps.stepped(topic), topic
    for topic in stepped[:-1]:  # all but z's command: nothing is whole yet
        steps.heard(topic, 0)
    steps.heard(topics.CUTTING_FORCE, 0)
    steps.heard(topics.GROUND_TRUTH, 0)
    assert steps.through == -1 and steps.behind() == [topics.joint_command('z')]


def test_the_graph_plan_is_what_the_runner_hears_of_the_job_as_prepared() -> None:
    """The runner's session and start read one value of the graph (jobs.base.GraphPlan)."""
    from mill_common import topics

    lockstep = job_for(scenario.load('slotting'))
    lockstep.prepare_graph(monitored=True)
    plan = lockstep.graph_plan()
    assert plan.steps is not None and plan.sim_time and not plan.late and not plan.timed
    assert dict(plan.kept) == lockstep.monitor_topics()
    assert plan.upstream == tuple(lockstep.upstream_topics())
    realtime = _realtime_slotting()
    realtime.prepare_graph(monitored=True)
    plan = realtime.graph_plan()
    assert plan.steps is None and not plan.sim_time
    assert plan.late == {topics.REFERENCE} and topics.joint_command('x') in plan.timed
    assert plan.late_after == tuple(topics.state(a) for a in 'xyz')


def test_the_record_kind_says_how_two_records_of_a_job_differ() -> None:
    # what `--compare-offline` prints: the record kind compares, signal by signal
    from mill_bringup.cli import set_duration
    from mill_bringup.jobs.base import simulate

    scen = scenario.load('slotting')
    set_duration(scen, 0.3)
    job = job_for(scen)
    rec, again = simulate(job), simulate(job)
    assert job.RECORD.differences(rec, again) == {'tracking_error': 0.0, 'cutting_force': 0.0}
    again.signals['position'][100, 1] += 1e-6  # y 1 µm off at one sample
    assert job.RECORD.differences(rec, again)['tracking_error'] == pytest.approx(1e-6, rel=1e-6)
    assert job.RECORD.gaps(rec) == {} and job.RECORD.foreign(rec) == {}


def test_the_runner_keeps_past_the_record_only_the_messages_a_summary_reads() -> None:
    """Once the record is built the runner forgets every topic's messages but these: none
    of a lockstep job (its summary reads the record), the commands and states of a realtime
    one (their arrival times give the drive's figures)."""
    assert job_for(scenario.load('slotting')).summary_topics() == frozenset()
    realtime = _realtime_slotting()
    assert realtime.summary_topics() == {
        f'mill/{axis}/{kind}' for axis in 'xyz' for kind in ('state', 'joint_command')
    }
