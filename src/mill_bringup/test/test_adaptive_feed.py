"""The adaptive-feed job (Rubio 2013's force law on the Kline slotting job), offline: lockstep
override, the depth told from the tool's z, the end with the path, and its headline figures.

The distributed run equals this offline twin bit for bit (test/test_force_job.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mill_analysis.record import FORCE_CONTROL, RunRecord
from mill_bringup.docs_figures.runs import offline
from mill_bringup.jobs.axis import AxisJob, depth_stretches
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.registry import job_for
from mill_common.timebase import control_instant
from mill_trajectory.config import build_job

from mill_bringup import scenario

NAME = 'slotting_adaptive_feed'
COL = {name: i for i, name in enumerate(FORCE_CONTROL)}
# 1 mm of the deep cut, then the job holds for settle_time: a short job that ends by its path
pytestmark = pytest.mark.xdist_group('adaptive_feed')
SHORT = ('trajectory.program.segments=["linear -0.075 -0.104 -0.005 0.003"]',)


def load(*overrides: str) -> scenario.Scenario:
    scen = scenario.load(NAME)
    for text in overrides:
        scen.add_override(text)
    return scen


@pytest.fixture(scope='module')
def whole() -> tuple[AxisJob, RunRecord]:
    # the run the docs' check (group adaptive_feed, same xdist worker) also uses
    return job_for(load()), offline(NAME)


def test_the_job_ends_settle_time_after_its_path_ends() -> None:
    job = job_for(load(*SHORT))
    nominal = job.samples  # at override 1: 1 mm at 3 mm/s + 0.5 s
    rec = simulate(job)
    assert job.samples == len(rec.t) != nominal
    tv = job.scenario.parameters(job.trajectory)
    end = build_job({**tv, 'settle_time': 0.0}).trajectory.sample(10.0).position
    # the reference reaches the end of the path settle_time (500 samples) before the end ...
    arrived = len(rec.t) - 1 - job.end.settle_samples
    assert job.end.settle_samples == 500
    ref = rec['reference'][:, :2]
    assert np.all(ref[arrived:] == end[:2])
    # ... and not a sample earlier (the y reference moves at a few µm per sample)
    assert ref[arrived - 1, 1] < end[1]
    # the force law slowed the feed (peak force above 300 N at override 1): a longer job
    assert len(rec.t) > nominal


def test_the_override_is_set_at_each_control_instant_from_that_samples_force(whole) -> None:
    job, rec = whole
    rows = rec.force_control
    dt_ns = job.dt_ns
    instants = [control_instant(j, 1 / 30, dt_ns) for j in range(len(rows))]
    assert np.allclose(rows[:, COL['t']], np.array(instants) * 1e-3, atol=0, rtol=1e-15)
    # between instants the reference moves at the override times the programmed 3 mm/s
    k0, k1 = instants[40], instants[41]
    v = rec['reference_velocity'][k0:k1, 1]
    assert np.all(v == pytest.approx(rows[40, COL['override']] * 0.003, rel=1e-12))
    # the depth told is the tool's depth below the top, from the measured z at the instant
    z = rec['position'][instants, 2]
    assert np.allclose(rows[:, COL['depth']], -z * 1e3, atol=1e-12)


def test_headline_figures_of_the_adaptive_feed_job(whole) -> None:
    """The figures docs/papers.md gives (printed to 0.1 N and 1e-4 of the override)."""
    _, rec = whole
    # The run is deterministic (bit-equal across processes); the tolerances are the
    # rounding of the printed figures.
    assert rec.t[-1] == pytest.approx(7.837, abs=5e-4)
    deep, shallow = depth_stretches(rec.force_control)
    assert (deep.depth, shallow.depth) == (5.0, 2.0)
    assert deep.force == pytest.approx(299.9, abs=0.05)
    assert deep.override == pytest.approx(0.8066, abs=5e-5)
    # the shallow cut needs 2.02 times the programmed feed: the law sits at the 200 % limit
    assert shallow.force == pytest.approx(297.4, abs=0.05)
    assert shallow.override == 2.0


def test_the_law_holds_its_depth_where_the_tool_is_not_in_the_work() -> None:
    from mill_controllers.force_control import ForceFeedLoop, parameter_specs

    values = {name: spec.default for name, spec in parameter_specs()}
    loop = ForceFeedLoop.from_parameters(values)
    assert loop.step(0.0, 1200.0, 0.0, depth=3.0).depth == 3.0
    assert loop.step(0.1, 1200.0, 0.0, depth=-1.0).depth == 3.0  # above the top: kept
    assert loop.step(0.2, 1200.0, 0.0).depth == 2.0  # no depth given: the time profile's


@pytest.mark.parametrize(
    ('override', 'message'),
    [
        ('trajectory.feed_override.period=0.02', 'not the force controller'),
        ('force_controller.override.max=1.5', 'differs from the force controller'),
        ('trajectory.feed_override.period=0.0', 'needs the trajectory'),
    ],
)
def test_a_job_whose_parts_do_not_fit_is_refused(override: str, message: str) -> None:
    with pytest.raises(scenario.ScenarioError, match=message):
        job_for(load(override))


def test_a_path_that_may_never_end_is_refused() -> None:
    scen = load('trajectory.feed_override.min=0.0', 'force_controller.override.min=0.0')
    with pytest.raises(scenario.ScenarioError, match='may never end'):
        job_for(scen)
    scen.add_override('trajectory.duration=2.0')  # a cap: fine
    assert job_for(scen).max_samples == 2001


def test_an_asynchronous_override_has_no_offline_twin() -> None:
    job = job_for(load('trajectory.feed_override.lockstep=false'))
    with pytest.raises(scenario.ScenarioError, match='no offline twin'):
        simulate(job)


def test_force_sampler_takes_the_peak_of_each_revolution() -> None:
    from mill_controllers.force_control import ForceSampler

    s = ForceSampler(1 / 30, 'resultant', 'peak')
    assert s.offer(0, (3.0, 4.0, 0.0)) == (0, 5.0)
    got = [s.offer(k * 1_000_000, (float(k), 0.0, 0.0)) for k in range(1, 35)]
    assert all(g is None for g in got[:-1])  # samples 1 .. 33 ms: no instant
    assert got[-1] == (1, 34.0)  # 34 ms is the first sample at or after 33.3 ms
    nan = ForceSampler(1 / 30, 'x', 'peak')
    nan.offer(0, (1.0, 0.0, 0.0))
    nan.offer(1_000_000, (math.nan, 0.0, 0.0))
    assert math.isnan(nan.offer(34_000_000, (2.0, 0.0, 0.0))[1])  # the law will hold
