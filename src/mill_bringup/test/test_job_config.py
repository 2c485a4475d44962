"""The job configuration: every shipped scenario passes every rule, and each rule, broken
by an override of a shipped scenario, names the two sides that disagree."""

from __future__ import annotations

from pathlib import Path

import pytest
from mill_bringup.cli import set_timing
from mill_bringup.job_config import (
    RULES,
    Failure,
    JobConfig,
    JobConfigError,
    Side,
    build,
    check,
    command_unit,
    cores_build,
    disturbance_unit,
    feed_limits,
    following_band,
    force_model,
    gains_for_the_rate,
    law_disturbance_unit,
    model_provided,
    one_command_delay,
    one_sample_period,
    override_period,
    override_range,
    travel_inside,
)
from mill_bringup.jobs.registry import job_for
from mill_controllers.pd_law import AdrcController
from mill_controllers.registry import CONTROLLERS

from mill_bringup import scenario

CONFIG = Path(__file__).resolve().parents[3] / 'config'
SHIPPED = sorted(CONFIG.glob('*.yaml'))


def runs(path: Path) -> dict[str, scenario.Scenario]:
    scen = scenario.load(str(path))
    return {name: scen.variant(name) for name in scen.variants} or {'': scen}


def broken(name: str, *overrides: str, variant: str = '') -> scenario.Scenario:
    scen = scenario.load(name)
    if variant:
        scen = scen.variant(variant)
    for text in overrides:
        scen.add_override(text)
    return scen


def failures_of(scen: scenario.Scenario) -> list[Failure]:
    """Every failure, from the error the builder raises (or none)."""
    try:
        build(scen, all_failures=True)
    except JobConfigError as exc:
        return exc.failures
    return []


@pytest.mark.parametrize('path', SHIPPED, ids=lambda p: p.stem)
def test_every_shipped_scenario_passes_every_rule(path: Path) -> None:
    for name, run in runs(path).items():
        config = build(run)
        assert check(config) == [], name
        realtime = runs(path)[name]
        if not all(n.kind.declares('timing') for n in realtime.nodes):
            continue  # the force job and the force controller have no realtime form
        set_timing(realtime, 'realtime')  # as run_scenario --timing realtime: delay 1 each
        assert check(build(realtime)) == [], name


def test_the_configuration_holds_what_the_jobs_read() -> None:
    config = build(scenario.load('maharof').variant('pi_imbdo'))
    assert config.sample_period == 1e-4 and config.axes == ('x',)
    x = config.axis('x')
    assert (x.controller, x.observer, x.delay) == ('x_controller', 'x_observer', 0)
    assert (x.output_unit, x.input_unit, x.disturbance_unit) == ('V', 'V', 'V')
    assert x.law is CONTROLLERS.get('cascade_pi')
    with pytest.raises(TypeError):
        config.node('plant').values['sample_period'] = 1.0  # type: ignore[index]
    rubio = build(scenario.load('rubio').variant('zoh'))
    assert rubio.sample_period == pytest.approx(60.0 / 715.0) and rubio.axes == ()
    assert rubio.period_source.node == 'force_process'


def test_one_sample_period_names_the_node_that_differs_and_the_job_period() -> None:
    (failure,) = one_sample_period(
        build_unchecked(broken('slotting', 'x_controller.sample_period=0.002'))
    )
    assert failure.rule == 'sample_period'
    assert failure.sides == (
        Side('plant', 'sample_period', 0.001),
        Side('x_controller', 'sample_period', 0.002),
    )
    assert '\n' not in failure.message and 'x_controller' in failure.message


def test_the_force_job_runs_at_one_spindle_revolution() -> None:
    scen = broken('rubio', 'trajectory.sample_period=0.1', variant='zoh')
    (failure,) = failures_of(scen)
    assert failure.sides == (
        Side('force_process', 'spindle revolution 60/S_s', 60.0 / 715.0),
        Side('trajectory', 'sample_period', 0.1),
    )
    with pytest.raises(scenario.ScenarioError, match=r"trajectory's sample_period is 0.1 s"):
        build(scen)


def test_gains_designed_for_another_rate_name_the_node() -> None:
    failures = failures_of(broken('beltran', '*.sample_period=0.002'))
    assert {f.rule for f in failures} == {'design_period'}
    assert [f.sides[0].node for f in failures] == [
        f'{a}_{role}' for role in ('observer', 'controller') for a in 'xyz'
    ]
    assert failures[0].sides == (
        Side('x_observer', 'design_period', 0.001),
        Side('plant', 'sample_period', 0.002),
    )
    assert failures_of(broken('beltran', '*.sample_period=0.002', '*.design_period=0.002')) == []


def test_one_command_delay_per_axis() -> None:
    (failure,) = one_command_delay(
        build_unchecked(broken('slotting', 'y_observer.command_delay=1'))
    )
    assert failure.rule == 'command_delay'
    assert failure.sides == (
        Side('y_controller', 'command_delay', 0),
        Side('y_observer', 'command_delay', 1),
    )
    drive = failures_of(broken('slotting', 'plant.command_delay=2'))
    assert [f.sides for f in drive] == [
        (Side(f'{a}_controller', 'command_delay', 0), Side('plant', 'command_delay', 2))
        for a in 'xyz'
    ]
    realtime = broken('slotting')
    set_timing(realtime, 'realtime')
    realtime.add_override('plant.command_delay=3')  # a realtime drive ignores it
    assert failures_of(realtime) == []


def test_the_command_unit_is_the_axis_models_input_unit() -> None:
    (failure,) = command_unit(
        build_unchecked(broken('slotting', 'x_controller.controller=cascade_pi'))
    )
    assert failure.rule == 'command_unit'
    assert failure.sides == (
        Side('x_controller', 'controller cascade_pi OUTPUT_UNIT', 'V'),
        Side('plant', 'axis_model rigid (x) INPUT_UNIT', 'N·m'),
    )
    scen = broken('hatwesh', 'plant.axis_model=[rigid,rigid,rigid]', variant='machine_pi')
    (failure,) = failures_of(scen)
    assert failure.sides == (
        Side('x_controller', 'controller machine_pi OUTPUT_UNIT', 'V'),
        Side('plant', 'axis_model rigid (x) INPUT_UNIT', 'N·m'),
    )


def test_the_observers_disturbance_unit_is_the_laws() -> None:
    # adrc reads an acceleration, pd reads no disturbance at all.
    assert law_disturbance_unit(AdrcController) == 'm/s²'
    assert (
        failures_of(broken('slotting', 'x_controller.controller=pd', 'x_observer.observer=imbdo'))
        == []
    )
    (failure,) = disturbance_unit(build_unchecked(broken('slotting', 'x_observer.observer=imbdo')))
    assert failure.rule == 'disturbance_unit'
    assert failure.sides == (
        Side('x_observer', 'observer imbdo DISTURBANCE_UNIT', 'V'),
        Side('x_controller', 'controller adrc DISTURBANCE_UNIT', 'm/s²'),
    )


def test_a_law_that_needs_a_model_has_an_observer_that_provides_one() -> None:
    scen = broken('hatwesh', 'x_observer.observer=dfo', variant='adaptive_pi_rls')
    (failure,) = model_provided(build_unchecked(scen))
    assert failure.rule == 'model'
    assert failure.sides == (
        Side('x_controller', 'controller adaptive_pi needs_model', True),
        Side('x_observer', 'observer dfo PROVIDES_MODEL', False),
    )
    with pytest.raises(scenario.ScenarioError, match=r'x_observer \(observer dfo\).*rls'):
        build(scen)
    # adaptive_pi with its own estimator needs none
    assert failures_of(broken('hatwesh', 'x_observer.observer=dfo', variant='adaptive_pi')) == []


@pytest.mark.parametrize(
    ('travel', 'sides'),
    [
        (
            'trajectory.travel.min=[-0.078,-1.0,-1.0]',
            (
                Side('x_controller', 'following_error_limit', 0.003),
                Side('trajectory', 'travel.min (x)', -0.078),
            ),
        ),
        (
            'trajectory.travel.max=[1.0,-0.1,1.0]',
            (
                Side('y_controller', 'following_error_limit', 0.003),
                Side('trajectory', 'travel.max (y)', -0.1),
            ),
        ),
    ],
)
def test_the_following_error_band_stays_inside_the_travel(
    travel: str, sides: tuple[Side, Side]
) -> None:
    (failure,) = following_band(build_unchecked(broken('identify', travel)))
    assert failure.rule == 'following_band' and failure.sides == sides
    assert f'axis {sides[1].name[-2]} may leave the machine travel' in failure.message
    # 6 mm from the end: room for 2 mm of approach and the 3 mm band
    assert failures_of(broken('identify', 'trajectory.travel.min=[-0.081,-1.0,-1.0]')) == []


def test_the_builder_says_the_first_failure_in_one_line_or_all() -> None:
    scen = broken('slotting', 'x_controller.sample_period=0.002', 'plant.command_delay=1')
    with pytest.raises(JobConfigError) as first:
        build(scen)
    assert str(first.value) == first.value.failures[0].message
    assert '\n' not in str(first.value)
    assert [f.rule for f in first.value.failures] == ['sample_period', *['command_delay'] * 3]
    with pytest.raises(JobConfigError) as every:
        build(scen, all_failures=True)
    assert str(every.value) == '; '.join(f.message for f in every.value.failures)


def test_a_missing_axis_node_is_refused_before_the_rules() -> None:
    scen = broken('maharof', 'plant.axes=[x,y]', variant='pi')
    with pytest.raises(scenario.ScenarioError, match=r"axes \['y'\] lack a controller"):
        build(scen)


def test_the_trajectory_travel_lies_inside_the_drive_travel() -> None:
    # The drive's guard would stop y at -0.2 m, where the trajectory allows -1 m.
    scen = broken('slotting', 'plant.travel.min=[-1.0,-0.2,-1.0]')
    (failure,) = travel_inside(build_unchecked(scen))
    assert failure.rule == 'travel'
    assert failure.sides == (
        Side('trajectory', 'travel.min (y)', -1.0),
        Side('plant', 'travel.min (y)', -0.2),
    )
    assert "axis y: the trajectory allows travel.min -1 m (trajectory) beyond the drive's" in (
        failure.message
    )
    # A drive's travel wider than the trajectory's is what a job near the end needs.
    wider = broken('slotting', 'trajectory.travel.max=[0.5,0.5,0.5]')
    assert travel_inside(build_unchecked(wider)) == []
    assert failures_of(broken('slotting', 'plant.travel.max=[1.0,1.0,0.9]'))[0].rule == 'travel'


def build_unchecked(scen: scenario.Scenario) -> JobConfig:
    """The configuration without its rules checked (to test one rule alone)."""
    return build(scen, rules=())


def test_every_rule_is_in_the_table() -> None:
    assert (
        cores_build,
        one_sample_period,
        gains_for_the_rate,
        one_command_delay,
        command_unit,
        disturbance_unit,
        model_provided,
        following_band,
        travel_inside,
        force_model,
        feed_limits,
        override_range,
        override_period,
    ) == RULES


@pytest.mark.parametrize('name', ['slotting', 'rubio', 'slotting_adaptive_feed'])
def test_the_job_validates_each_node_once(name: str, monkeypatch) -> None:
    scen = scenario.load(name)
    if scen.variants:
        scen = scen.variant(next(iter(scen.variants)))
    calls: list[str] = []
    validate = scenario.Scenario.parameters

    def counted(self: scenario.Scenario, node: str) -> dict:
        calls.append(node)
        return validate(self, node)

    monkeypatch.setattr(scenario.Scenario, 'parameters', counted)
    job = job_for(scen)
    job.simulation()
    job.prepare_graph(monitored=True, layout='per_axis')  # its processes from the config
    assert sorted(calls) == sorted(n.name for n in scen.nodes)


def test_the_force_controller_designs_with_the_process_the_plant_runs() -> None:
    scen = broken('rubio', 'force_controller.force_process.flutes=2', variant='zoh')
    (failure,) = force_model(build_unchecked(scen))
    assert failure.rule == 'force_model'
    assert failure.sides == (
        Side('force_process', 'force_process.flutes', 4),
        Side('force_controller', 'force_process.flutes', 2),
    )
    with pytest.raises(scenario.ScenarioError, match=r'disagree on force_process\.flutes'):
        job_for(scen)


def test_the_force_process_feed_range_is_the_controllers() -> None:
    scen = broken('rubio', 'force_process.feed_limits=[0.0, 30.0]', variant='zoh')
    (failure,) = feed_limits(build_unchecked(scen))
    assert failure.rule == 'feed_limits'
    assert failure.sides == (
        Side('force_process', 'feed_limits', [0.0, 30.0]),
        Side('force_controller', 'override range × nominal_feed', [0.0, 20.0]),
    )


def test_the_trajectory_clamps_the_override_to_the_controllers_range() -> None:
    scen = broken('slotting_adaptive_feed', 'trajectory.feed_override.max=1.5')
    (failure,) = failures_of(scen)
    assert failure.rule == 'override_range'
    assert failure.sides == (
        Side('trajectory', 'feed_override.min, .max', [0.1, 1.5]),
        Side('force_controller', 'override.min, .max', [0.1, 2.0]),
    )
    assert override_range(build_unchecked(scen)) == [failure]


def test_a_lockstep_override_comes_once_per_spindle_revolution() -> None:
    scen = broken('slotting_adaptive_feed', 'trajectory.feed_override.period=0.01')
    (failure,) = override_period(build_unchecked(scen))
    assert failure.rule == 'override_period'
    assert failure.sides == (
        Side('trajectory', 'feed_override.period', 0.01),
        Side('force_controller', 'spindle revolution 60/S_s', 60.0 / 1800.0),
    )
    assert failures_of(scen) == [failure]


def test_a_gain_no_law_builds_with_is_a_typed_failure_and_stops_the_checks() -> None:
    # Issue 37: gpi.omega_n = 1e300 overflows in gpi's design, running or not; the rules
    # after cores_build build the cores too, so it is the one failure.
    scen = scenario.load('slotting')
    scen.add_override('x_controller.gpi.omega_n=1e300')
    scen.add_override('y_observer.dfo.omega_o=1e300')
    failures = check(build_unchecked(scen))
    assert [f.rule for f in failures] == ['cores_build', 'cores_build']
    by_node = {f.sides[0].node: f for f in failures}
    law, given = by_node['x_controller'].sides
    assert (law.name, law.value) == ('controller', 'adrc')
    assert given.name == 'values' and given.value['gpi.omega_n'] == 1e300
    assert by_node['x_controller'].message == (
        'x_controller: controller adrc cannot run with its values: gpi (not the running law): '
        "OverflowError: (34, 'Numerical result out of range')"
    )
    assert 'dfo (not the running observer): OverflowError' in by_node['y_observer'].message
