"""The runner's own figures of a realtime run with an external driver (jobs.realtime)."""

from __future__ import annotations

import math

import numpy as np
from mill_bringup.jobs.realtime import command_timing
from mill_bringup.metrics import SIGNALS, RunRecord
from mill_common.ros import joint_state_bytes

from mill_common import topics

T0 = 1_800_000_000_000_000_000  # the job's start on the system clock [ns]
DT = 10_000_000


class Received:
    """A MessageSource that only says when each command arrived."""

    def __init__(self, arrivals: list[int]) -> None:
        self.arrivals = arrivals

    def arrival_ns(self, topic: str) -> list[int]:
        return self.arrivals


def test_late_fraction_and_latency_count_the_jobs_states_only() -> None:
    n = 4
    rec = RunRecord(np.arange(n) * DT * 1e-9, {s: np.full((n, 3), math.nan) for s in SIGNALS})
    # Answered: a state before the job (hold), job states 0, 1 and 3, and one after the job
    # that the runner took 3 s late while it ended the run.
    stamps = [T0 - DT, T0, T0 + DT, T0 + 3 * DT, T0 + 9 * DT]
    lags = [1_000_000, 2_000_000, 4_000_000, 3_000_000, 3_000_000_000]
    raw = {topics.joint_command('x'): [joint_state_bytes(s, ('x',), effort=(0.0,)) for s in stamps]}
    source = Received([s + lag for s, lag in zip(stamps, lags, strict=True)])
    got = command_timing(rec, raw, source, ['x'], T0)['x']  # type: ignore[arg-type]
    assert got['late_fraction'] == 0.25  # job state 2 got no command
    assert got['latency_median_ms'] == 3.0
    assert got['latency_max_ms'] == 4.0  # not the 3 s of the command after the job
