"""One validated job configuration, built once before any process starts. ROS-free.

`build(scen)` validates every node's parameters once (the scenario, its params files and
overrides merged, as each node will hold them) and checks the rules that span nodes; the
result, a frozen `JobConfig`, is what the job, the offline simulator, the runner, the
launch plan and `tune` read. Each rule is a small function of the configuration returning
typed `Failure`s (the rule, the two sides, the one-line message), so a caller or a test
reads which two values disagree without parsing a message:

- `cores_build`: every axis controller and observer builds its cores from its values, the
  running law or observer and each other one given gains other than its defaults (issue
  37: a gain that overflows is refused before any process starts, in one line);
- `sample_period`: every node that has a sample period runs at the job's one (the plant's,
  or the force process's spindle revolution);
- `design_period`: gains designed for one rate (a node's design_period) run at that rate;
- `command_delay`: per axis, the controller, the observer and (lockstep) the drive count the
  same samples of command delay;
- `command_unit`: the law's command (OUTPUT_UNIT) is what the axis model takes (INPUT_UNIT);
- `disturbance_unit`: the observer's disturbance (DISTURBANCE_UNIT) is in the unit the law
  reads it in, for a law that declares one (DISTURBANCE_UNIT on the law class);
- `model`: a law that designs with the observer's model (needs_model) has an observer that
  provides one (PROVIDES_MODEL);
- `following_band`: every axis, anywhere within its following-error limit of the path,
  stays inside the trajectory's travel;
- `travel`: the trajectory's travel lies inside the drive's (whose motion guard stops an
  axis about to leave it, mill_plant.motion_guard): a path the trajectory allows is never
  cut short by the drive;
- with a force controller: `force_model`, it designs with the process model the force
  process runs; `feed_limits`, the force process's feed range is the controller's override
  range times its nominal feed; `override_range`, the trajectory clamps the override to the
  controller's range; `override_period`, an axis job's lockstep override comes once per
  control period (one spindle revolution of the controller's model).
"""

from __future__ import annotations

from types import MappingProxyType

from mill_common.build_check import BUILD_ERRORS, build_failure
from mill_common.parameters import algorithm_values
from mill_common.signals import AXES
from mill_controllers.registry import CONTROLLERS
from mill_models.force_process import ForceProcessModel
from mill_observers.registry import OBSERVERS
from mill_plant.registry import AXIS_MODELS

from mill_bringup.catalogue import CONTROLLER, FORCE_PROCESS, OBSERVER, PLANT
from mill_bringup.job_config_types import (
    AxisConfig,
    Failure,
    JobConfig,
    JobConfigError,
    NodeConfig,
    Rule,
    Side,
)
from mill_bringup.job_rules_cores import (
    command_unit,
    cores_build,
    disturbance_unit,
    law_disturbance_unit,
    model_provided,
)
from mill_bringup.job_rules_force import feed_limits, force_model, override_period, override_range
from mill_bringup.job_rules_timing import gains_for_the_rate, one_command_delay, one_sample_period
from mill_bringup.job_rules_travel import following_band, travel_inside
from mill_bringup.scenario import Scenario, ScenarioError

# The configuration's public names: the builder and the rules here, what they build and
# report, and each rule (tests check one at a time).
__all__ = [
    'RULES',
    'Failure',
    'JobConfig',
    'JobConfigError',
    'Rule',
    'Side',
    'build',
    'check',
    'command_unit',
    'cores_build',
    'disturbance_unit',
    'feed_limits',
    'following_band',
    'force_model',
    'gains_for_the_rate',
    'law_disturbance_unit',
    'model_provided',
    'one_command_delay',
    'one_sample_period',
    'override_period',
    'override_range',
    'travel_inside',
]

# In the order a failure is reported: the first is the most basic.
RULES: tuple[Rule, ...] = (
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
)


def check(c: JobConfig, rules: tuple[Rule, ...] = RULES) -> list[Failure]:
    """Every failure of every rule, in the rules' order; none after cores_build's (the
    other rules build the cores too)."""
    out = []
    for rule in rules:
        found = rule(c)
        out += found
        if found and rule is cores_build:
            break
    return out


def _period_source(scen: Scenario, nodes: tuple[NodeConfig, ...]) -> Side:
    """The job's sample period: the plant's, the force process's spindle revolution, or the
    first node's that has one."""
    for n in nodes:
        if n.role == PLANT:
            return Side(n.name, 'sample_period', n.values['sample_period'])
    for n in nodes:
        if n.role == FORCE_PROCESS:
            model = ForceProcessModel.from_parameters(algorithm_values(ForceProcessModel, n.values))
            return Side(n.name, 'spindle revolution 60/S_s', model.sample_period)
    for n in nodes:
        if n.declares('sample_period'):
            return Side(n.name, 'sample_period', n.values['sample_period'])
    raise ScenarioError(f'scenario {scen.name}: no node has a sample period')


def _axis_configs(scen: Scenario, nodes: tuple[NodeConfig, ...]) -> dict[str, AxisConfig]:
    plants = [n for n in nodes if n.role == PLANT]
    if not plants:
        return {}
    pv = plants[0].values
    per_axis: dict[tuple[str, str], NodeConfig] = {}
    for n in nodes:
        if n.kind.per_axis:
            per_axis[(n.values['axis'], n.role)] = n
    missing = [
        a for a in pv['axes'] if (a, CONTROLLER) not in per_axis or (a, OBSERVER) not in per_axis
    ]
    if missing:
        raise ScenarioError(
            f'scenario {scen.name}: axes {missing} lack a controller or an observer'
        )
    out = {}
    for axis in pv['axes']:
        ctrl, obs = per_axis[(axis, CONTROLLER)], per_axis[(axis, OBSERVER)]
        out[axis] = AxisConfig(
            axis,
            ctrl.name,
            obs.name,
            CONTROLLERS.get(ctrl.values['controller']),
            OBSERVERS.get(obs.values['observer']),
            AXIS_MODELS.get(pv['axis_model'][AXES.index(axis)]),
            int(ctrl.values['command_delay']),
        )
    return out


def build(scen: Scenario, all_failures: bool = False, rules: tuple[Rule, ...] = RULES) -> JobConfig:
    """The scenario's job configuration, every node validated once and every rule checked.

    ScenarioError (one line) for a value a node refuses; JobConfigError (a ScenarioError:
    the first failure's line, or every one's if all_failures) for a broken rule. `rules`:
    which to check (all of them, but for a test of one).
    """
    nodes = tuple(
        NodeConfig(n.name, n.kind, MappingProxyType(scen.parameters(n.name))) for n in scen.nodes
    )
    plants = [n for n in nodes if n.role == PLANT]
    try:
        source = _period_source(scen, nodes)
    except BUILD_ERRORS as exc:  # a force process model that cannot be built
        raise ScenarioError(f'scenario {scen.name}: {build_failure(exc)}') from None
    config = JobConfig(
        scenario=scen.name,
        nodes=nodes,
        sample_period=float(source.value),
        period_source=source,
        timing=str(plants[0].values.get('timing', 'lockstep')) if plants else 'lockstep',
        axes=tuple(plants[0].values['axes']) if plants else (),
        axis_configs=MappingProxyType(_axis_configs(scen, nodes)),
    )
    failures = check(config, rules)
    if failures:
        raise JobConfigError(failures, all_failures)
    return config
