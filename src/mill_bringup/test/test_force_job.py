"""Force-job scenarios; J_c from their force stream equals the offline loop's (ROS-free)."""

from __future__ import annotations

import pytest
from mill_analysis.force_record import continuous_cost
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.force import ForceJob
from mill_bringup.jobs.registry import job_for

from mill_bringup import scenario

RUBIO = ('zoh', 'beta_neg0.3', 'scheme1', 'scheme2')


def rubio(variant: str) -> scenario.Scenario:
    return scenario.load('rubio').variant(variant)


@pytest.mark.parametrize('name', RUBIO)
def test_rubio_variants_are_consistent_force_jobs(name: str) -> None:
    job = job_for(rubio(name))
    assert isinstance(job, ForceJob)
    assert job.samples == 120 and job.period == 60.0 / 715.0
    assert job.controller_values['reference_force'] == 1200.0


def test_cost_from_the_stream_equals_the_loop_cost() -> None:
    job = job_for(rubio('beta_neg0.3'))
    rec = simulate(job)
    design = job.design()
    j_c = continuous_cost(rec.trace_ns, rec.trace_force, 1200.0, design.damping, design.omega_n)
    assert j_c == pytest.approx(rec.j_c, rel=1e-7)


def test_plant_and_controller_must_share_the_process_model() -> None:
    scen = rubio('zoh')
    scen.add_override('force_controller.force_process.flutes=2')
    with pytest.raises(scenario.ScenarioError, match='flutes'):
        job_for(scen)
    scen = rubio('zoh')
    scen.add_override('force_process.feed_limits=[0.0, 30.0]')
    with pytest.raises(scenario.ScenarioError, match='feed_limits'):
        job_for(scen)
