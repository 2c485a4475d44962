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

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from mill_common.build_check import BUILD_ERRORS, build_failure
from mill_common.parameters import algorithm_values
from mill_common.signals import AXES
from mill_controllers.base import AxisController
from mill_controllers.config import build_controller, build_loop, check_other_laws
from mill_controllers.force_control import ForceFeedLoop
from mill_controllers.registry import CONTROLLERS
from mill_models.force_process import ForceProcessModel
from mill_observers.base import Observer
from mill_observers.config import build_observer_loop, check_other_observers
from mill_observers.registry import OBSERVERS
from mill_plant.models.base import AxisModel
from mill_plant.registry import AXIS_MODELS
from mill_trajectory.config import JobPath, build_job

from mill_bringup.catalogue import (
    CONTROLLER,
    FORCE_CONTROLLER,
    FORCE_PROCESS,
    OBSERVER,
    PLANT,
    TRAJECTORY,
    NodeKind,
)
from mill_bringup.scenario import Scenario, ScenarioError

# Two sample periods closer than this (relative) are the same period.
PERIOD_TOLERANCE = 1e-12


@dataclass(frozen=True)
class Side:
    """One side of a rule: a node, the value's name there, the value."""

    node: str
    name: str
    value: Any


@dataclass(frozen=True)
class Failure:
    """A rule the configuration breaks: its name, the two sides that disagree, and why."""

    rule: str
    sides: tuple[Side, Side]
    message: str  # one line naming both sides

    def __str__(self) -> str:
        return self.message


class JobConfigError(ScenarioError):
    """The configuration breaks rules; str() is the first failure's message (one line), or
    every failure's, joined, if built with all_failures."""

    def __init__(self, failures: list[Failure], all_failures: bool = False) -> None:
        self.failures = list(failures)
        shown = self.failures if all_failures else self.failures[:1]
        super().__init__('; '.join(f.message for f in shown))


@dataclass(frozen=True)
class NodeConfig:
    """One node: what it is and its validated parameter values (read-only)."""

    name: str
    kind: NodeKind
    values: Mapping[str, Any]

    @property
    def role(self) -> str:
        return self.kind.role

    def declares(self, name: str) -> bool:
        return name in self.values


@dataclass(frozen=True)
class AxisConfig:
    """An active axis: its controller and observer nodes, their classes, the plant's model."""

    axis: str
    controller: str  # node name
    observer: str  # node name
    law: type[AxisController]
    observer_class: type[Observer]
    plant_model: type[AxisModel]
    delay: int  # the controller's command_delay (the rule: every side's)

    @property
    def output_unit(self) -> str:
        return self.law.OUTPUT_UNIT

    @property
    def input_unit(self) -> str:
        return self.plant_model.INPUT_UNIT

    @property
    def disturbance_unit(self) -> str:
        return self.observer_class.DISTURBANCE_UNIT


@dataclass(frozen=True)
class JobConfig:
    """A scenario's nodes with their validated values, and what the jobs read of them."""

    scenario: str  # its name, for messages
    nodes: tuple[NodeConfig, ...]
    sample_period: float  # [s] the job's (the plant's, the force process's revolution, ...)
    period_source: Side  # where sample_period comes from
    timing: str  # the plant's timing ('lockstep' without a plant)
    axes: tuple[str, ...]  # the plant's active axes (none without a plant)
    axis_configs: Mapping[str, AxisConfig]  # per active axis
    _built: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    def node(self, name: str) -> NodeConfig:
        for n in self.nodes:
            if n.name == name:
                return n
        raise ScenarioError(f'scenario {self.scenario} has no node {name!r}')

    def values(self, name: str) -> dict[str, Any]:
        """A node's validated values (a copy: the configuration does not change)."""
        return dict(self.node(name).values)

    def of_role(self, role: str) -> list[NodeConfig]:
        return [n for n in self.nodes if n.role == role]

    def names_of(self, role: str) -> list[str]:
        return [n.name for n in self.of_role(role)]

    def axis(self, axis: str) -> AxisConfig:
        return self.axis_configs[axis]

    def delays(self) -> dict[str, int]:
        """command_delay of each active axis."""
        return {a: c.delay for a, c in self.axis_configs.items()}

    @property
    def plant(self) -> str | None:
        names = self.names_of(PLANT)
        return names[0] if names else None

    @property
    def trajectory(self) -> str | None:
        names = self.names_of(TRAJECTORY)
        return names[0] if len(names) == 1 else None

    def trajectory_job(self) -> JobPath:
        """The trajectory node's job (path and end), built once."""
        if 'trajectory' not in self._built:
            name = self.trajectory
            if name is None:
                raise ScenarioError(f'scenario {self.scenario}: an axis job has one trajectory')
            try:
                self._built['trajectory'] = build_job(self.values(name))
            except ScenarioError:
                raise
            except ValueError as exc:  # the path leaves the travel, the job is too long
                raise ScenarioError(f'{name}: {exc}') from None
        job: JobPath = self._built['trajectory']
        return job


# -- the rules ------------------------------------------------------------------------------
Rule = Callable[[JobConfig], list[Failure]]


def _same_period(a: float, b: float) -> bool:
    return abs(a - b) <= PERIOD_TOLERANCE * max(abs(a), abs(b))


def one_sample_period(c: JobConfig) -> list[Failure]:
    """Every node that declares sample_period runs at the job's sample period."""
    ref = c.period_source
    out = []
    for n in c.nodes:
        if n.name == ref.node or not n.declares('sample_period'):
            continue
        mine = Side(n.name, 'sample_period', n.values['sample_period'])
        if not _same_period(mine.value, ref.value):
            out.append(
                Failure(
                    'sample_period',
                    (ref, mine),
                    f"scenario {c.scenario}: {mine.node}'s sample_period is {mine.value!r} s "
                    f"but {ref.node}'s {ref.name} is {ref.value!r} s: every node of a job runs "
                    'at one sample period (set it once, under /**)',
                )
            )
    return out


def gains_for_the_rate(c: JobConfig) -> list[Failure]:
    """A node's gains designed for one sample period (design_period) run at that period."""
    ref = c.period_source
    out = []
    for n in c.nodes:
        designed = n.values.get('design_period') or 0.0
        if not designed or _same_period(designed, ref.value):
            continue
        mine = Side(n.name, 'design_period', designed)
        out.append(
            Failure(
                'design_period',
                (mine, ref),
                f"scenario {c.scenario}: {n.name}'s gains were designed for T = "
                f'{1e3 * designed:g} ms (design_period) but the job runs at T = '
                f"{1e3 * ref.value:g} ms ({ref.node}'s {ref.name}): give gains for this rate, "
                'or the tuning rule (observer eso with eso.omega_o 0, pd.omega_c 0) and '
                'design_period 0',
            )
        )
    return out


def one_command_delay(c: JobConfig) -> list[Failure]:
    """Per axis, the controller aims, the observer predicts and (lockstep) the drive applies
    each command the same samples late. A realtime drive has one sample by nature and
    ignores its command_delay."""
    out = []
    plant = c.plant
    for axis, a in c.axis_configs.items():
        ctrl = Side(a.controller, 'command_delay', c.node(a.controller).values['command_delay'])
        others = [Side(a.observer, 'command_delay', c.node(a.observer).values['command_delay'])]
        if plant is not None and c.timing == 'lockstep':
            others.append(Side(plant, 'command_delay', c.node(plant).values['command_delay']))
        for other in others:
            if other.value != ctrl.value:
                out.append(
                    Failure(
                        'command_delay',
                        (ctrl, other),
                        f'scenario {c.scenario}: axis {axis}: {ctrl.node} has command_delay '
                        f'{ctrl.value} but {other.node} {other.value}: the drive applies each '
                        'command, the observer predicts with it and the controller aims that '
                        'many samples late; give them one (run_scenario --delay N)',
                    )
                )
    return out


def command_unit(c: JobConfig) -> list[Failure]:
    """The law commands the unit the plant's axis model takes."""
    out = []
    plant = c.plant
    for axis, a in c.axis_configs.items():
        if a.output_unit == a.input_unit or plant is None:
            continue
        law = c.node(a.controller).values['controller']
        model = c.node(plant).values['axis_model'][AXES.index(axis)]
        mine = Side(a.controller, f'controller {law} OUTPUT_UNIT', a.output_unit)
        theirs = Side(plant, f'axis_model {model} ({axis}) INPUT_UNIT', a.input_unit)
        out.append(
            Failure(
                'command_unit',
                (mine, theirs),
                f'scenario {c.scenario}: axis {axis}: {a.controller} runs {law}, which commands '
                f'{a.output_unit}, but {plant} drives it with axis model {model}, which takes '
                f'{a.input_unit}: use a law and an axis model with the same unit',
            )
        )
    return out


def law_disturbance_unit(law: type[AxisController]) -> str | None:
    """The unit a law reads the observer's disturbance in, if its class declares one
    (DISTURBANCE_UNIT); None: the law declares none, and the rule does not apply."""
    unit = getattr(law, 'DISTURBANCE_UNIT', None)
    return unit if isinstance(unit, str) else None


def disturbance_unit(c: JobConfig) -> list[Failure]:
    """The observer estimates the disturbance in the unit the law reads it in."""
    out = []
    for axis, a in c.axis_configs.items():
        wanted = law_disturbance_unit(a.law)
        if wanted is None or wanted == a.disturbance_unit:
            continue
        law = c.node(a.controller).values['controller']
        kind = c.node(a.observer).values['observer']
        mine = Side(a.observer, f'observer {kind} DISTURBANCE_UNIT', a.disturbance_unit)
        theirs = Side(a.controller, f'controller {law} DISTURBANCE_UNIT', wanted)
        out.append(
            Failure(
                'disturbance_unit',
                (mine, theirs),
                f'scenario {c.scenario}: axis {axis}: {a.observer} (observer {kind}) estimates '
                f'the disturbance in {a.disturbance_unit} but {a.controller} ({law}) reads it '
                f'in {wanted}: use an observer whose estimate the law can use',
            )
        )
    return out


def _nothing(_values: dict[str, Any]) -> None:
    """(A force controller builds its one law at start-up, and switches to no other.)"""


def cores_build(c: JobConfig) -> list[Failure]:
    """Every axis controller, observer and force controller can build its cores from its
    values, as the node does at start-up: the running law or observer, and each other one
    given gains other than its defaults (a switch to it later must not fail). Its design
    period is the rule design_period's, so it is left out here."""
    builds: dict[str, tuple[str, Callable[[dict[str, Any]], Any], Callable[..., None]]] = {
        CONTROLLER: ('controller', build_loop, check_other_laws),
        OBSERVER: ('observer', build_observer_loop, check_other_observers),
        FORCE_CONTROLLER: ('force_controller', ForceFeedLoop.from_parameters, _nothing),
    }
    out = []
    for n in c.nodes:
        if n.role not in builds:
            continue
        choice, build, check_others = builds[n.role]
        values = {**n.values, 'design_period': 0.0}
        try:
            build(values)
            check_others(values)
        except BUILD_ERRORS as exc:
            defaults = {k: spec.default for k, spec in n.kind.parameter_specs()}
            given = {k: v for k, v in n.values.items() if v != defaults.get(k)}
            out.append(
                Failure(
                    'cores_build',
                    (Side(n.name, choice, values[choice]), Side(n.name, 'values', given)),
                    f'{n.name}: {choice} {values[choice]} cannot run with its values: '
                    f'{build_failure(exc)}',
                )
            )
    return out


def model_providers() -> list[str]:
    """The observers that provide a model (PROVIDES_MODEL)."""
    return [name for name in OBSERVERS if OBSERVERS.get(name).PROVIDES_MODEL]


def model_provided(c: JobConfig) -> list[Failure]:
    """A law that designs with the observer's model (needs_model) has an observer that
    provides one (PROVIDES_MODEL). needs_model belongs to the law as built (adaptive_pi: its
    model_source), so the law is built to ask it; its gains' rate is design_period's rule."""
    out = []
    for axis, a in c.axis_configs.items():
        if a.observer_class.PROVIDES_MODEL:
            continue
        values = {**c.node(a.controller).values, 'design_period': 0.0}
        if not build_controller(values).needs_model:
            continue
        law = values['controller']
        kind = c.node(a.observer).values['observer']
        mine = Side(a.controller, f'controller {law} needs_model', True)
        theirs = Side(a.observer, f'observer {kind} PROVIDES_MODEL', False)
        out.append(
            Failure(
                'model',
                (mine, theirs),
                f'scenario {c.scenario}: axis {axis}: {a.controller} ({law}) designs with the '
                f"observer's model estimate, but {a.observer} (observer {kind}) estimates none "
                f'(use observer {" or ".join(model_providers())})',
            )
        )
    return out


def following_band(c: JobConfig) -> list[Failure]:
    """Every axis, anywhere within its following-error limit of the path, stays inside the
    machine's travel (the trajectory's travel.min / travel.max): a controller trips only
    beyond that limit, so the whole band must fit, as before an identify run."""
    if c.plant is None or c.trajectory is None:
        return []
    trajectory = c.trajectory
    tv = c.node(trajectory).values
    limits: dict[int, Side] = {}
    for n in c.of_role(CONTROLLER):
        i = AXES.index(n.values['axis'])
        limits[i] = Side(n.name, 'following_error_limit', float(n.values['following_error_limit']))
    lo, hi = c.trajectory_job().trajectory.bounds(tv['sample_period'])
    out = []
    for i, axis in enumerate(AXES):
        limit = limits.get(i, Side(trajectory, 'path', 0.0))
        b = limit.value if math.isfinite(limit.value) else 0.0
        for edge, sign, end, side in (
            (lo[i], -1.0, tv['travel.min'][i], 'min'),
            (hi[i], 1.0, tv['travel.max'][i], 'max'),
        ):
            if sign * (edge + sign * b - end) > 0.0:
                travel = Side(trajectory, f'travel.{side} ({axis})', end)
                out.append(
                    Failure(
                        'following_band',
                        (limit, travel),
                        f'scenario {c.scenario}: axis {axis} may leave the machine travel '
                        f'before its controller trips: its path reaches {edge:.6g} m and its '
                        f'following-error limit is {1e3 * b:g} mm ({limit.node}), beyond '
                        f"travel.{side} {end:g} m ({trajectory}'s); move the axis or lower "
                        'the limit',
                    )
                )
    return out


def travel_inside(c: JobConfig) -> list[Failure]:
    """The trajectory's travel (which the path is checked against) lies inside the drive's
    (which its motion guard keeps every axis in): both are the machine's travel, declared
    once (mill_common.travel); the drive's may only be the wider."""
    if c.plant is None or c.trajectory is None:
        return []
    pv, tv = c.node(c.plant).values, c.node(c.trajectory).values
    if 'travel.min' not in pv:  # a plant without a drive's guard (the force process)
        return []
    out = []
    for i, axis in enumerate(AXES):
        for side, sign in (('min', -1.0), ('max', 1.0)):
            name = f'travel.{side}'
            path, drive = tv[name][i], pv[name][i]
            if sign * (path - drive) > 0.0:
                out.append(
                    Failure(
                        'travel',
                        (
                            Side(c.trajectory, f'{name} ({axis})', path),
                            Side(c.plant, f'{name} ({axis})', drive),
                        ),
                        f'scenario {c.scenario}: axis {axis}: the trajectory allows {name} '
                        f"{path:g} m ({c.trajectory}) beyond the drive's {drive:g} m "
                        f'({c.plant}), which stops the axis there; give them one travel',
                    )
                )
    return out


def _one(c: JobConfig, role: str) -> NodeConfig | None:
    nodes = c.of_role(role)
    return nodes[0] if len(nodes) == 1 else None


def _process_model(values: Mapping[str, Any]) -> dict[str, Any]:
    return algorithm_values(ForceProcessModel, dict(values))


def force_model(c: JobConfig) -> list[Failure]:
    """The force controller designs with the process model the force process runs."""
    plant, ctrl = _one(c, FORCE_PROCESS), _one(c, FORCE_CONTROLLER)
    if plant is None or ctrl is None:
        return []
    runs, designs = _process_model(plant.values), _process_model(ctrl.values)
    out = []
    for key in sorted(k for k in runs if runs[k] != designs.get(k)):
        name = f'{ForceProcessModel.PREFIX}.{key}'
        out.append(
            Failure(
                'force_model',
                (Side(plant.name, name, runs[key]), Side(ctrl.name, name, designs.get(key))),
                f'scenario {c.scenario}: {plant.name} and {ctrl.name} disagree on {name} '
                f'({runs[key]!r} and {designs.get(key)!r}): the controller designs with the '
                'process model the plant runs',
            )
        )
    return out


def feed_limits(c: JobConfig) -> list[Failure]:
    """The force process's feed range is the controller's override range times its feed."""
    plant, ctrl = _one(c, FORCE_PROCESS), _one(c, FORCE_CONTROLLER)
    if plant is None or ctrl is None:
        return []
    cv = ctrl.values
    wanted = [cv['override.min'] * cv['nominal_feed'], cv['override.max'] * cv['nominal_feed']]
    given = list(plant.values['feed_limits'])
    if given == wanted:
        return []
    return [
        Failure(
            'feed_limits',
            (
                Side(plant.name, 'feed_limits', given),
                Side(ctrl.name, 'override range × nominal_feed', wanted),
            ),
            f"scenario {c.scenario}: {plant.name}'s feed_limits {given} differ from "
            f"{ctrl.name}'s override range times nominal_feed, [{wanted[0]:g}, {wanted[1]:g}] "
            'mm/s',
        )
    ]


def override_range(c: JobConfig) -> list[Failure]:
    """The trajectory clamps the feed override to the force controller's override range."""
    ctrl, trajectory = _one(c, FORCE_CONTROLLER), c.trajectory
    if ctrl is None or trajectory is None:
        return []
    tv, cv = c.node(trajectory).values, ctrl.values
    if not tv['feed_override.enabled']:
        return []
    mine = [tv['feed_override.min'], tv['feed_override.max']]
    theirs = [cv['override.min'], cv['override.max']]
    if mine == theirs:
        return []
    return [
        Failure(
            'override_range',
            (
                Side(trajectory, 'feed_override.min, .max', mine),
                Side(ctrl.name, 'override.min, .max', theirs),
            ),
            f"scenario {c.scenario}: {trajectory}'s feed_override range [{mine[0]:g}, "
            f"{mine[1]:g}] differs from the force controller's override range "
            f"[{theirs[0]:g}, {theirs[1]:g}] ({ctrl.name}'s override.min, .max)",
        )
    ]


def override_period(c: JobConfig) -> list[Failure]:
    """An axis job's lockstep feed override comes once per control period, one spindle
    revolution of the force controller's model (the trajectory's feed_override.period)."""
    ctrl, trajectory = _one(c, FORCE_CONTROLLER), c.trajectory
    if c.plant is None or ctrl is None or trajectory is None:
        return []
    tv = c.node(trajectory).values
    given = tv['feed_override.period']
    if not (tv['feed_override.enabled'] and tv['feed_override.lockstep'] and given > 0):
        return []  # no lockstep override, or a period not given (the job says so)
    period = ForceProcessModel.from_parameters(_process_model(ctrl.values)).sample_period
    if _same_period(given, period):
        return []
    return [
        Failure(
            'override_period',
            (
                Side(trajectory, 'feed_override.period', given),
                Side(ctrl.name, 'spindle revolution 60/S_s', period),
            ),
            f"scenario {c.scenario}: {trajectory}'s feed_override.period {given!r} s is not "
            f"the force controller's control period ({ctrl.name}'s spindle revolution 60/S_s "
            f'= {period!r} s)',
        )
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


# -- the builder ----------------------------------------------------------------------------
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
