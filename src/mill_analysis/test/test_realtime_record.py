"""How the commands of a realtime run answered the job's states (the runner's summary, the
report of a bag): realtime_record.command_timing; and the samples of the drive's sequence a
realtime record lacks per topic: realtime_record.missing_ticks."""

from __future__ import annotations

import math

import numpy as np
from mill_analysis.realtime_record import (
    command_timing,
    longest_run,
    missing_ticks,
    realtime_record,
)
from mill_analysis.record import SIGNALS, RunRecord
from mill_common.ros import joint_state_bytes

from mill_common import topics

T0 = 1_800_000_000_000_000_000  # the job's start on the system clock [ns]
DT = 10_000_000


def test_late_fraction_and_latency_count_the_jobs_states_only() -> None:
    n = 4
    rec = RunRecord(np.arange(n) * DT * 1e-9, {s: np.full((n, 3), math.nan) for s in SIGNALS})
    # Answered: a state before the job (hold), job states 0, 1 and 3, and one after the job
    # that the runner took 3 s late while it ended the run.
    stamps = [T0 - DT, T0, T0 + DT, T0 + 3 * DT, T0 + 9 * DT]
    lags = [1_000_000, 2_000_000, 4_000_000, 3_000_000, 3_000_000_000]
    raw = {topics.joint_command('x'): [joint_state_bytes(s, ('x',), effort=(0.0,)) for s in stamps]}
    arrivals = {topics.joint_command('x'): [s + lag for s, lag in zip(stamps, lags, strict=True)]}
    got = command_timing(rec, raw, arrivals, ['x'], T0)['x']
    assert got.unanswered == 0.25  # job state 2 got no command
    assert list(got.latency_ms) == [2.0, 4.0, 3.0]  # not the hold's, not the 3 s after the job
    figures = got.figures()
    assert figures['late_fraction'] == 0.25
    assert figures['longest_late_run'] == 1
    assert (figures['latency_median_ms'], figures['latency_max_ms']) == (3.0, 4.0)


def test_the_longest_run_counts_consecutive_misses_only() -> None:
    assert longest_run([]) == 0
    assert longest_run([False, True, False, True, True, True, False, True]) == 3
    assert longest_run([True] * 5) == 5


def test_a_command_whose_arrival_is_unknown_counts_as_answer_but_not_in_latency() -> None:
    rec = RunRecord(np.array([0.0]), {s: np.full((1, 3), math.nan) for s in SIGNALS})
    raw = {topics.joint_command('y'): [joint_state_bytes(T0, ('y',), effort=(0.0,))]}
    got = command_timing(rec, raw, {topics.joint_command('y'): [None]}, ['y'], T0)['y']
    assert got.unanswered == 0.0 and got.latency_ms.size == 0 and got.longest_unanswered == 0
    assert math.isnan(got.figures()['latency_median_ms'])


def test_a_topic_lacks_the_ticks_the_other_drive_topics_hold() -> None:
    got = missing_ticks({'a': [1, 2, 3, 4, 5], 'b': [1, 3, 5], 'c': [2, 5], 'd': []})
    assert got == {'a': 0, 'b': 2, 'c': 2, 'd': 0}
    assert missing_ticks({'a': [5, 6], 'b': [5, 6]}) == {'a': 0, 'b': 0}


def test_ticks_before_a_topics_first_or_after_its_last_are_not_counted() -> None:
    # A recorder that joins a running graph subscribes to its topics one after the other.
    got = missing_ticks({'a': [1, 2, 3, 4], 'b': [3, 4], 'c': [1, 2]})
    assert got == {'a': 0, 'b': 0, 'c': 0}


def test_a_realtime_record_counts_the_drives_ticks_missing_per_topic() -> None:
    # The drive ticked ten times in the job (and once before it, once after): y's state lost
    # ticks 2 and 3, the ground truth tick 7, x's state tick 6.
    # A state of y from another sender, stamped off the drive's ticks, is no tick.
    ticks = [T0 + k * DT for k in range(-1, 11)]
    lost = {'x': {6}, 'y': {2, 3}, 'truth': {7}}

    def sent(what: str, make) -> list[bytes]:
        return [make(ns) for k, ns in enumerate(ticks, -1) if k not in lost.get(what, ())]

    raw = {
        topics.state(a): sent(a, lambda ns, a=a: joint_state_bytes(ns, (a,), (0.0,), sender='d'))
        for a in 'xy'
    }
    raw[topics.state('y')].append(joint_state_bytes(T0 + DT // 2, ('y',), (1.0,), sender='m'))
    truth = (0.0, 0.0)
    raw[topics.GROUND_TRUTH] = sent('truth', lambda ns: joint_state_bytes(ns, 'xy', *[truth] * 3))
    owners = {topics.state(a): 'd' for a in 'xy'}
    rec, missing = realtime_record(raw, ['x', 'y'], T0, 9 * DT * 1e-9, owners)
    assert missing == {topics.state('x'): 1, topics.state('y'): 2, topics.GROUND_TRUTH: 1}
    assert rec.t.size == 9  # x's states of ticks 0 .. 9 but 6
    assert np.isnan(rec.signals['position'][2:4, 1]).all()
    assert not np.isnan(rec.signals['position'][[0, 1, 4], 1]).any()
    assert rec.foreign == {topics.state('y'): 1}  # the other sender's state, left out


def test_a_realtime_record_without_ground_truth_counts_the_states_only() -> None:
    raw = {topics.state('x'): [joint_state_bytes(T0 + k * DT, ('x',), (0.0,)) for k in range(3)]}
    _, missing = realtime_record(raw, ['x'], T0, 2 * DT * 1e-9)
    assert missing == {topics.state('x'): 0}
