"""Offline simulator: the scenario's cores composed in one process, without ROS.

It performs, sample by sample, exactly the calls the distributed graph makes
(plant measure -> observer correct -> controller -> plant step, observer
predict), so the two agree to floating-point precision. Used for tests,
parameter sweeps and as the reference of the distributed run.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Callable

from mill_common.signals import AXES, axis_index
from mill_common.timebase import period_ns, seconds
from mill_controllers.config import build_controller
from mill_observers.config import build_observer
from mill_plant.config import build_plant
from mill_plant.sensor import quantize
from mill_trajectory.config import build_job

from mill_bringup import force_job, papers
from mill_bringup import scenario as scenario_mod
from mill_bringup.metrics import RunRecord, format_summary, summarize


def job_steps(end_time: float, dt_ns: int) -> int:
    """Samples of a job: k = 0 .. the first k with t_k >= end_time (when the job is done)."""
    k = max(0, math.ceil(end_time * 1e9 / dt_ns) - 1)
    while seconds(k * dt_ns) < end_time:
        k += 1
    while k > 0 and seconds((k - 1) * dt_ns) >= end_time:
        k -= 1
    return k + 1


class CoreTimes:
    """Time spent in each role's core during a simulation (`benchmark --cores`).

    perf_counter, not process_time: the cores take about a µs, and reading the process's
    CPU clock costs a system call of about that much. Per call means per sample and axis
    (the observer's correct and predict together), per sample for the plant and trajectory.
    """

    ROLES = ('trajectory', 'observer', 'controller', 'plant')

    def __init__(self) -> None:
        self.seconds = dict.fromkeys(self.ROLES, 0.0)
        self.calls = dict.fromkeys(self.ROLES, 0)
        self._t = time.perf_counter()

    def start(self) -> None:
        self._t = time.perf_counter()

    def lap(self, role: str, call: bool = True) -> None:
        now = time.perf_counter()
        self.seconds[role] += now - self._t
        self.calls[role] += call
        self._t = now

    def per_call_us(self) -> dict[str, float]:
        return {r: 1e6 * self.seconds[r] / max(self.calls[r], 1) for r in self.ROLES}


class _NoTimes:
    def start(self) -> None:
        pass

    def lap(self, role: str, call: bool = True) -> None:
        pass


def simulate(
    scen: scenario_mod.Scenario,
    progress: Callable[[float, float], None] | None = None,
    times: CoreTimes | None = None,
) -> RunRecord:
    plant_name = scen.nodes_of('mill_plant')[0].name
    pv = scen.parameters(plant_name)
    tv = scen.parameters(scen.nodes_of('mill_trajectory')[0].name)
    plant = build_plant(pv)
    job = build_job(tv)
    dt_ns = period_ns(pv['sample_period'])
    dt = seconds(dt_ns)
    controllers, observers = build_axis_cores(scen)
    active = [i for i, a in enumerate(AXES) if a in pv['axes']]
    resolution = pv['sensor_resolution']

    n = job_steps(job.end_time, dt_ns)
    rec = RunRecord.empty(n, dt)
    s = rec.signals
    torque = [math.nan] * len(AXES)
    clock = times or _NoTimes()
    for k in range(n):
        t = seconds(k * dt_ns)
        clock.start()
        ref = job.trajectory.sample(t)
        clock.lap('trajectory')
        position = plant.position
        for i in active:
            y = quantize(position[i], resolution)
            clock.start()
            est = observers[i].correct(y)
            clock.lap('observer')
            torque[i] = controllers[i].compute(t, y, ref.axis(i), est)
            clock.lap('controller')
            s['position'][k, i] = y
            s['reference'][k, i] = ref.position[i]
            s['reference_velocity'][k, i] = ref.velocity[i]
            s['estimate_velocity'][k, i] = est.velocity
            s['estimate_disturbance'][k, i] = est.disturbance
            s['torque'][k, i] = torque[i]
        u = tuple(torque)
        s['true_velocity'][k] = plant.velocity
        s['true_disturbance'][k] = plant.disturbance(u)
        s['force'][k] = plant.cutting_force()
        clock.start()
        plant.step(u, dt)
        clock.lap('plant')
        for i in active:
            observers[i].predict(torque[i])
            clock.lap('observer', call=False)  # the second half of the correct call's sample
        if progress and k % 1000 == 0:
            progress(t, job.end_time)
    return rec


def build_axis_cores(scen: scenario_mod.Scenario) -> tuple[dict[int, object], dict[int, object]]:
    """Controller and observer cores by axis index, checked to fit together.

    ScenarioError if an active axis lacks one, or if a controller designs with the
    observer's model estimate (adaptive_pi model_source observer) and the observer of its
    axis estimates none.
    """
    pv = scen.parameters(scen.nodes_of('mill_plant')[0].name)
    controllers: dict[int, object] = {}
    observers: dict[int, object] = {}
    names: dict[int, str] = {}
    for node in scen.nodes_of('mill_controllers'):
        values = scen.parameters(node.name)
        controllers[axis_index(values['axis'])] = build_controller(values)
    for node in scen.nodes_of('mill_observers'):
        values = scen.parameters(node.name)
        i = axis_index(values['axis'])
        observers[i] = build_observer(values)
        names[i] = f'{node.name} (observer {values["observer"]})'
    active = [i for i, a in enumerate(AXES) if a in pv['axes']]
    missing = [AXES[i] for i in active if i not in controllers or i not in observers]
    if missing:
        raise scenario_mod.ScenarioError(
            f'scenario {scen.name}: axes {missing} lack a controller or an observer'
        )
    for i in active:
        wants = getattr(controllers[i], 'needs_model', False)
        if wants and not getattr(type(observers[i]), 'PROVIDES_MODEL', False):
            raise scenario_mod.ScenarioError(
                f"scenario {scen.name}: the {AXES[i]} controller designs with the observer's "
                f'model estimate, but {names[i]} estimates none (use observer rls)'
            )
    return controllers, observers


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog='offline_sim',
        description='Run a scenario offline (all cores in one process, no ROS) and print '
        'its metrics.',
    )
    parser.add_argument('scenario', nargs='?', default='slotting', help='name or YAML file')
    parser.add_argument('--param', '-p', action='append', default=[], metavar='NODE.NAME=VALUE')
    parser.add_argument('--controller', help='shortcut for *_controller.controller=NAME')
    parser.add_argument('--duration', type=float, help='end the job after this time [s]')
    parser.add_argument('--skip', type=float, default=1.0, help='metrics from this time on [s]')
    parser.add_argument(
        '--variant', help="run only this one of the scenario's variants (default: all of them)"
    )
    args = parser.parse_args(argv)
    records = {}
    try:
        scen = scenario_mod.load(args.scenario)
        apply_cli_overrides(scen, args)
        for name, variant in variants(scen, args.variant).items():
            if force_job.is_force_job(variant):
                print(force_job.format_offline(variant.name, force_job.simulate_offline(variant)))
                continue
            t0 = time.monotonic()
            rec = records[name] = simulate(variant)
            wall = time.monotonic() - t0
            if name:
                print(f'variant {name}:')
            print(format_summary(summarize(rec, args.skip), args.skip))
            print(f'{rec.t[-1]:.3f} s simulated in {wall:.2f} s wall')
    except scenario_mod.ScenarioError as exc:
        print(f'offline_sim: error: {exc}', file=sys.stderr)
        return 2
    text = papers.report(scen.paper, records)
    if text:
        print(text)
    return 0


def variants(
    scen: scenario_mod.Scenario, only: str | None = None
) -> dict[str, scenario_mod.Scenario]:
    """The configurations to run: every variant of the scenario, one, or the scenario itself."""
    if only:
        return {only: scen.variant(only)}
    if not scen.variants:
        return {'': scen}
    return {name: scen.variant(name) for name in scen.variants}


def apply_cli_overrides(scen: scenario_mod.Scenario, args: argparse.Namespace) -> None:
    """--param, --controller and --duration, shared by the runner and offline_sim."""
    for text in args.param:
        scen.add_override(text)
    if args.controller:
        scen.add_override(f'*_controller.controller={args.controller}')
    if args.duration is not None:
        if not args.duration > 0:
            raise scenario_mod.ScenarioError(f'--duration must be > 0, got {args.duration}')
        for node in scen.nodes_of('mill_trajectory'):
            scen.add_override(f'{node.name}.duration={args.duration!r}')


if __name__ == '__main__':
    raise SystemExit(main())
