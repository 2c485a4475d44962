"""Command-line options every scenario command shares (run_scenario, offline_sim, benchmark)."""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from mill_common.declared import Configured, ParamSet

from mill_bringup.catalogue import CONTROLLER, OBSERVER, PLANT, TRAJECTORY
from mill_bringup.job_config import JobConfig
from mill_bringup.scenario import Scenario, ScenarioError, apply_params_file, load

# --tuning: the gains of the tuning rule (mill_models.loop_tuning) instead of the scenario's
TUNINGS = ('rule',)


def add_scenario_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument('scenario', nargs='?', default='slotting', help='name or YAML file')
    parser.add_argument(
        '--param',
        '-p',
        action='append',
        default=[],
        metavar='NODE.NAME=VALUE',
        help='override a node parameter; NODE may be a glob',
    )
    parser.add_argument(
        '--params-file',
        action='append',
        default=[],
        metavar='FILE',
        help='a ROS 2 parameter file applied on top of the scenario, before any --param '
        '(e.g. the one tune writes); repeatable',
    )
    parser.add_argument(
        '--controller', help='the law of every axis controller (shortcut for -p, e.g. pd)'
    )
    parser.add_argument('--duration', type=float, help='end the job after this time [s]')
    parser.add_argument(
        '--delay',
        type=int,
        metavar='N',
        help='samples between the measurement a command is computed from and the period it '
        'acts in: the plant applies each command N steps late, the observers and controllers '
        'compensate for N (command_delay)',
    )
    parser.add_argument(
        '--timing',
        choices=('lockstep', 'realtime'),
        help='lockstep (the plant is the clock; the default of the scenarios) or realtime '
        '(the plant keeps the wall clock and holds the newest command, as a drive does)',
    )
    parser.add_argument(
        '--tuning',
        choices=TUNINGS,
        help='rule: the ADRC law and the ESO observer of every axis at the bandwidths of the '
        'tuning rule for the sample period and the command delay (mill_models.loop_tuning), '
        "instead of the scenario's gains, which are designed for its own rate",
    )
    parser.add_argument(
        '--skip',
        type=float,
        default=1.0,
        help='metrics over t >= SKIP (start transient excluded) [s]',
    )
    parser.add_argument(
        '--program',
        metavar='FILE.ngc',
        help='run this G-code part program (trajectory gcode, planned within the gcode.max_* '
        "limits) from where the scenario's job starts",
    )
    parser.add_argument(
        '--resume-after',
        type=float,
        metavar='SECONDS',
        help="a program's pause (M0, M1) ends by itself after this long at rest "
        '(gcode.resume_after): nobody resumes it in an unattended run',
    )
    parser.add_argument(
        '--variant', help="run only this one of the scenario's variants (default: all of them)"
    )


def apply_overrides(scen: Scenario, args: argparse.Namespace) -> None:
    """--params-file, --param, --controller and --duration."""
    for path in getattr(args, 'params_file', []):
        apply_params_file(scen, path)
    for text in args.param:
        scen.add_override(text)
    if args.controller:
        axis_controllers = scen.nodes_of(CONTROLLER)
        if not axis_controllers:
            raise ScenarioError(f'--controller: scenario {scen.name} has no axis controller')
        for node in axis_controllers:
            scen.add_override(f'{node.name}.controller={args.controller}')
    set_timing(scen, getattr(args, 'timing', None), getattr(args, 'delay', None))
    if getattr(args, 'tuning', None):
        set_tuning(scen)
    if getattr(args, 'program', None):
        set_program(scen, args.program)
    if getattr(args, 'resume_after', None) is not None:
        set_resume_after(scen, args.resume_after)
    if args.duration is not None:
        set_duration(scen, args.duration)


def set_program(scen: Scenario, program: str) -> None:
    """--program: every trajectory node runs this G-code file, from its job's start point,
    and the plant's cutting follows the program's spindle (spindle: reference)."""
    from mill_trajectory.config import build_job

    path = Path(program).resolve()
    if not path.is_file():
        raise ScenarioError(f'--program: {program}: no such G-code file')
    for node in scen.nodes_of(TRAJECTORY):
        start = build_job(scen.parameters(node.name)).trajectory.sample(0.0).position
        scen.add_override(f'{node.name}.trajectory=gcode')
        scen.add_override(f'{node.name}.gcode.file={json.dumps(str(path))}')
        scen.add_override(f'{node.name}.gcode.start={json.dumps(list(start))}')
        try:  # read, checked and planned whole before anything starts
            build_job(scen.parameters(node.name))
        except ValueError as exc:
            raise ScenarioError(f'--program: {exc}') from None
    for node in scen.nodes_of(PLANT):  # the program switches the spindle (M3/M4/M5)
        if scen.parameters(node.name).get('spindle') is not None:
            scen.add_override(f'{node.name}.spindle=reference')


def set_timing(scen: Scenario, timing: str | None, delay: int | None = None) -> None:
    """--timing and --delay on every node that has them."""
    if timing:
        for node in scen.nodes:
            scen.add_override(f'{node.name}.timing={timing}')
            if timing == 'realtime':
                scen.add_override(f'{node.name}.use_sim_time=false')
    if delay is None and timing == 'realtime':
        delay = 1  # a command computed from the state of tick k acts from tick k + 1
    if delay is not None:
        if delay < 0:
            raise ScenarioError(f'--delay must be a whole number >= 0, got {delay}')
        for node in scen.nodes:
            if node.kind.declares('command_delay'):
                scen.add_override(f'{node.name}.command_delay={delay}')


def declared(cls: type[Configured]) -> type[ParamSet]:
    """A core's parameter set, if it is the one its parameters come from (same PREFIX);
    a class that still writes PREFIX and PARAMETERS itself beside an inherited PARAMS
    (excitation under the adrc law's) declares none here."""
    return cls.PARAMS if cls.PARAMS.PREFIX == cls.PREFIX else ParamSet


def rule_laws() -> tuple[str, ...]:
    """The laws the tuning rule tunes (mill_models.loop_tuning): those whose parameters
    declare a rule quantity (a field whose 0 stands for the rule's value)."""
    from mill_controllers.registry import CONTROLLERS

    return tuple(name for name, cls in CONTROLLERS.items() if declared(cls).rule_fields())


def rule_observer() -> str:
    """The observer the tuning rule pairs with the laws: the first registered one whose
    parameters declare the rule's observer bandwidth (eso)."""
    from mill_observers.registry import OBSERVERS

    return next(
        name for name, cls in OBSERVERS.items() if 'omega_o' in declared(cls).rule_fields().values()
    )


def _rule_overrides(node: str, params: type[ParamSet]) -> list[str]:
    """Every rule field of a parameter set at 0 (the rule's value), by its full name."""
    return [f'{node}.{params.full_name(name)}=0.0' for name in params.rule_fields()]


def set_tuning(scen: Scenario) -> None:
    """--tuning rule: every axis's observer the rule's (eso), law and observer at the
    rule's bandwidths."""
    from mill_controllers.registry import CONTROLLERS
    from mill_observers.registry import OBSERVERS

    laws, observer = rule_laws(), rule_observer()
    for node in scen.nodes_of(CONTROLLER):
        law = scen.parameters(node.name)['controller']
        if law not in laws:
            raise ScenarioError(
                f'--tuning rule tunes the {" or ".join(laws)} law with the {observer} observer; '
                f'{node.name} runs {law}'
            )
        for text in _rule_overrides(node.name, declared(CONTROLLERS.get(law))):
            scen.add_override(text)
        scen.add_override(f'{node.name}.design_period=0.0')
    for node in scen.nodes_of(OBSERVER):
        scen.add_override(f'{node.name}.observer={observer}')
        for text in _rule_overrides(node.name, declared(OBSERVERS.get(observer))):
            scen.add_override(text)
        scen.add_override(f'{node.name}.design_period=0.0')


def set_resume_after(scen: Scenario, seconds: float) -> None:
    """--resume-after: a program's pauses end by themselves after this long at rest."""
    if not seconds > 0:
        raise ScenarioError(f'--resume-after must be > 0, got {seconds}')
    for node in scen.nodes_of(TRAJECTORY):
        scen.add_override(f'{node.name}.gcode.resume_after={seconds!r}')


def set_duration(scen: Scenario, duration: float) -> None:
    """--duration: the machine time the trajectory runs."""
    if not (duration > 0 and math.isfinite(duration)):
        raise ScenarioError(f'--duration must be a finite number > 0, got {duration}')
    for node in scen.nodes_of(TRAJECTORY):
        scen.add_override(f'{node.name}.duration={duration!r}')


def variants(scen: Scenario, only: str | None = None) -> dict[str, Scenario]:
    """The configurations to run: every variant of the scenario, one, or the scenario itself."""
    if only:
        return {only: scen.variant(only)}
    if not scen.variants:
        return {'': scen}
    return {name: scen.variant(name) for name in scen.variants}


def load_scenario(args: argparse.Namespace) -> tuple[Scenario, dict[str, Scenario]]:
    """The scenario named on the command line with its overrides, and the runs it asks for.

    The command line's overrides come last: they win over a variant's own.
    """
    scen = load(args.scenario)
    apply_overrides(scen, args)
    runs = variants(scen, args.variant)
    for run in runs.values():
        if run is not scen:
            apply_overrides(run, args)
    return scen, runs


def run_parameters(configs: Mapping[str, JobConfig]) -> dict[str, dict[str, dict[str, Any]]]:
    """Each run's validated node parameters (variant → node → name → value), from its job
    configuration: what a paper report names as the readings its figures rest on."""
    return {
        name: {node.name: dict(node.values) for node in config.nodes}
        for name, config in configs.items()
    }
