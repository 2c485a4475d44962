"""How the commands of a realtime run answered the job's states (the runner's summary, the
report of a bag): realtime_record.command_timing."""

from __future__ import annotations

import math

import numpy as np
from mill_analysis.metrics import SIGNALS, RunRecord
from mill_analysis.realtime_record import command_timing, longest_run
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
