"""The cutting-force job of Rubio 2013 across processes, its offline twin, and J_c from a record.

    run_scenario rubio_zoh --compare-offline
    offline_sim rubio_scheme1

A force-job scenario launches `force_process_node` (mill_plant), `force_controller_node`
(mill_controllers) and the trajectory with `feed_override.lockstep`. Per spindle revolution
k the plant publishes the force sample F_p(t_k); the controller answers with the override
o_k and its β-hold slope; the trajectory answers with the reference of sample k, whose
velocity and acceleration are the feed command and its ramp; the plant integrates the
revolution and publishes the force on a grid over it (/mill/cutting_force/trace).

The runner stops after the trajectory's `duration` (n = ⌈duration/T⌉ samples), and the
analysis computes the continuous-time cost of eq. (14) from the recorded force stream:

    J_c = Σ_j ∫ (F_p(τ) − F_pm(τ))² dτ [N²·s],

F_pm the continuous response of the reference model eq. (7) to the reference step at t = 0,
by Simpson's rule on each smooth piece of the stream (the plant repeats a point where the
force jumps or kinks: a depth change, a clamp corner, a sample boundary).
"""

from __future__ import annotations

import itertools
import math
import os
import signal
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from mill_common.env import ros_environment
from mill_common.parameters import algorithm_values
from mill_common.timebase import sample_stamp_ns
from mill_controllers.force_control import FORCE_CONTROLLERS, build_law
from mill_controllers.model_reference import DESIGN_PARAMETERS, ForceControlDesigner
from mill_models.force_process import ForceProcessModel
from mill_models.quadrature import simpson
from mill_models.reference_model import ContinuousReference

from mill_bringup import scenario as scenario_mod

PLANT_EXECUTABLE = ('mill_plant', 'force_process_node')
CONTROLLER_EXECUTABLE = ('mill_controllers', 'force_controller_node')


class ForceJobError(RuntimeError):
    """A force job that could not run to its end; str() says why."""


def is_force_job(scen: scenario_mod.Scenario) -> bool:
    return any((n.package, n.executable) == PLANT_EXECUTABLE for n in scen.nodes)


def _only(scen: scenario_mod.Scenario, key: tuple[str, str]) -> str:
    names = [n.name for n in scen.nodes if (n.package, n.executable) == key]
    if len(names) != 1:
        raise scenario_mod.ScenarioError(
            f'a force job needs exactly one {key[0]} {key[1]} node, scenario {scen.name} has '
            f'{len(names)}'
        )
    return names[0]


@dataclass(frozen=True)
class ForceJob:
    """What the scenario says about the job, checked for consistency."""

    plant: str
    controller: str
    trajectory: str
    model: ForceProcessModel
    controller_values: dict[str, Any]
    samples: int
    trace_intervals: int

    @property
    def period(self) -> float:
        return self.model.sample_period


def force_job(scen: scenario_mod.Scenario) -> ForceJob:
    plant = _only(scen, PLANT_EXECUTABLE)
    controller = _only(scen, CONTROLLER_EXECUTABLE)
    trajectories = scen.nodes_of('mill_trajectory')
    if len(trajectories) != 1:
        raise scenario_mod.ScenarioError('a force job needs exactly one trajectory node')
    pv = scen.parameters(plant)
    cv = scen.parameters(controller)
    tv = scen.parameters(trajectories[0].name)
    model_p = algorithm_values(ForceProcessModel, pv)
    model_c = algorithm_values(ForceProcessModel, cv)
    if model_p != model_c:
        diff = sorted(k for k in model_p if model_p[k] != model_c.get(k))
        raise scenario_mod.ScenarioError(
            f'plant and force controller disagree on force_process.{", ".join(diff)}'
        )
    model = ForceProcessModel.from_parameters(model_p)
    if not (tv['feed_override.enabled'] and tv['feed_override.lockstep']):
        raise scenario_mod.ScenarioError(
            'the trajectory of a force job needs feed_override.enabled and .lockstep'
        )
    if abs(tv['sample_period'] - model.sample_period) > 1e-12 * model.sample_period:
        raise scenario_mod.ScenarioError(
            f'trajectory sample_period {tv["sample_period"]!r} s is not one spindle '
            f'revolution, 60/S_s = {model.sample_period!r} s'
        )
    lo, hi = cv['override.min'] * cv['nominal_feed'], cv['override.max'] * cv['nominal_feed']
    if list(pv['feed_limits']) != [lo, hi]:
        raise scenario_mod.ScenarioError(
            f"plant feed_limits {pv['feed_limits']} differ from the controller's override "
            f'range times nominal_feed, [{lo:g}, {hi:g}] mm/s'
        )
    if not tv['duration'] > 0:
        raise scenario_mod.ScenarioError('a force job needs the trajectory duration > 0 [s]')
    n = max(1, math.ceil(tv['duration'] / model.sample_period - 1e-9))
    return ForceJob(plant, controller, trajectories[0].name, model, cv, n, pv['trace_intervals'])


# -- analysis ----------------------------------------------------------------------------


def smooth_pieces(stamps_ns: np.ndarray, values: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Split a force stream where a point is repeated (stamps at most 1 ns apart)."""
    stamps_ns = np.asarray(stamps_ns, dtype=np.int64)
    values = np.asarray(values, dtype=float)
    cuts = np.flatnonzero(np.diff(stamps_ns) <= 1) + 1
    pieces = []
    for s, v in zip(np.split(stamps_ns, cuts), np.split(values, cuts), strict=True):
        if len(s) >= 2:
            pieces.append((s / 1e9, v))
    return pieces


def continuous_cost(
    stamps_ns: np.ndarray,
    forces: np.ndarray,
    reference_force: float,
    damping: float,
    omega_n: float,
) -> float:
    """Rubio 2013 eq. (14) from a recorded force stream [N²·s] (see the module doc)."""
    # Rubio 2013 eq. (14): J_c = Σ_j ∫_{(j−1)T}^{jT} (F_p(τ) − F_pm(τ))² dτ
    f_ref = ContinuousReference(damping, omega_n)
    f_ref.reset(0.0, 0.0)
    f_ref.begin(reference_force)
    total = 0.0
    for times, force in smooth_pieces(stamps_ns, forces):
        total += simpson(times, (force - f_ref.values(times)) ** 2)
    return total


@dataclass
class ForceRecord:
    """Samples k = 0..n−1 of one force job and its force stream."""

    t: np.ndarray
    force: np.ndarray  # F_p(t_k) as measured [N]
    override: np.ndarray
    slope: np.ndarray  # β-hold slope of the override [1/s]
    beta: np.ndarray
    feed_command: np.ndarray  # the law's f_c,k [mm/s]
    trace_ns: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    trace_force: np.ndarray = field(default_factory=lambda: np.zeros(0))
    j_c: float = math.nan


def design_of(job: ForceJob) -> ForceControlDesigner:
    """The controller's reference model (ξ, ω_n) for J_c."""
    kind = job.controller_values['force_controller']
    values = algorithm_values(FORCE_CONTROLLERS[kind], job.controller_values)
    return ForceControlDesigner(job.model, **{p.name: values[p.name] for p in DESIGN_PARAMETERS})


# -- offline ------------------------------------------------------------------------------


def simulate_offline(scen: scenario_mod.Scenario, nan_samples: Sequence[int] = ()) -> ForceRecord:
    """The same job in one process (mill_bringup.force_loop), as a ForceRecord with J_c."""
    from mill_bringup.force_loop import simulate

    job = force_job(scen)
    cv = job.controller_values
    kind = cv['force_controller']
    nominal = cv['nominal_feed']
    law = build_law(
        kind,
        job.model,
        algorithm_values(FORCE_CONTROLLERS[kind], cv),
        cv['override.min'] * nominal,
        cv['override.max'] * nominal,
    )
    loop = {
        'reference_force': cv['reference_force'],
        'job_duration': job.samples * job.period,
        'nominal_feed': nominal,
        'override_min': cv['override.min'],
        'override_max': cv['override.max'],
        'intersample_intervals': job.trace_intervals,
    }
    rec = simulate(law, job.model, loop, nan_samples=nan_samples, keep_trace=True)
    ns = [np.rint(times * 1e9).astype(np.int64) for times, _, _ in rec.fine]
    return ForceRecord(
        rec.t,
        rec.force,
        rec.override,
        rec.slope,
        rec.beta,
        rec.feed_command,
        np.concatenate(ns) if ns else np.zeros(0, dtype=np.int64),
        np.concatenate([f for _, f, _ in rec.fine]) if rec.fine else np.zeros(0),
        rec.j_c,
    )


# -- distributed --------------------------------------------------------------------------


@dataclass
class ForceRunResult:
    scenario: str
    samples: int
    sim_time: float
    wall_time: float
    record: ForceRecord
    offline: ForceRecord | None = None

    def differences(self) -> dict[str, float]:
        """Largest |distributed − offline| per signal, and J_c's relative difference."""
        if self.offline is None:
            return {}
        a, b = self.record, self.offline
        out = {}
        for key in ('force', 'override', 'slope', 'beta', 'feed_command'):
            x, y = getattr(a, key), getattr(b, key)
            out[key] = float(np.max(np.abs(x - y))) if x.shape == y.shape else math.inf
        out['j_c_relative'] = abs(a.j_c - b.j_c) / abs(b.j_c)
        return out

    def to_json(self) -> dict:
        r = self.record
        return {
            'scenario': self.scenario,
            'samples': self.samples,
            'sim_time': self.sim_time,
            'wall_time': self.wall_time,
            'j_c': r.j_c,
            'j_c_offline': None if self.offline is None else self.offline.j_c,
            'differences': self.differences(),
            'mean_override': float(np.mean(r.override)),
            'beta_switches': int(np.count_nonzero(np.diff(r.beta))),
        }


def _monitor(feed_axis: str):
    """A node that keeps every force-job message it hears (built after rclpy.init)."""
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import WrenchStamped
    from mill_common.ros import DATA_QOS, from_duration, from_stamp
    from rclpy.node import Node
    from sensor_msgs.msg import JointState
    from trajectory_msgs.msg import JointTrajectory

    from mill_common import topics

    class ForceMonitor(Node):
        def __init__(self) -> None:
            super().__init__('force_job_monitor')
            self.force: dict[int, float] = {}
            self.trace: list[tuple[int, float]] = []
            self.trace_samples: set[int] = set()
            self.override: dict[int, tuple[float, float]] = {}
            self.state: dict[int, list[float]] = {}
            self.problems: list[str] = []

            def force(msg: WrenchStamped) -> None:
                self.force[from_stamp(msg.header.stamp)] = getattr(msg.wrench.force, feed_axis)

            def trace(msg: JointTrajectory) -> None:
                ns = from_stamp(msg.header.stamp)
                self.trace_samples.add(ns)
                for point in msg.points:
                    self.trace.append(
                        (ns + from_duration(point.time_from_start), point.positions[0])
                    )

            def override(msg: JointState) -> None:
                slope = msg.velocity[0] if len(msg.velocity) else 0.0
                self.override[from_stamp(msg.header.stamp)] = (msg.position[0], slope)

            def state(msg: JointState) -> None:
                self.state[from_stamp(msg.header.stamp)] = list(msg.position)

            def diagnostics(msg: DiagnosticArray) -> None:
                for s in msg.status:
                    if s.level != b'\x00' and s.level != 0:
                        self.problems.append(f'{s.name}: {s.message}')

            self.create_subscription(WrenchStamped, topics.CUTTING_FORCE, force, DATA_QOS)
            self.create_subscription(JointTrajectory, topics.CUTTING_FORCE_TRACE, trace, DATA_QOS)
            self.create_subscription(JointState, topics.FEED_OVERRIDE, override, DATA_QOS)
            self.create_subscription(JointState, topics.FORCE_CONTROL_STATE, state, DATA_QOS)
            self.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, diagnostics, 10)

    return ForceMonitor()


def run(
    scen: scenario_mod.Scenario,
    run_dir: Path,
    quiet: bool = False,
    domain_id: str | None = None,
    compare_offline: bool = False,
    stall_timeout: float = 30.0,
    startup_timeout: float = 120.0,
) -> ForceRunResult:
    """Run the force job across processes; the record holds samples 0..n−1 and the stream."""
    from mill_bringup.runner import Graph, Progress

    job = force_job(scen)
    # The plant waits for two listeners of the force samples: the controller and us.
    scen.overrides.setdefault(job.plant, {}).setdefault('min_subscribers', 2)
    feed_axis = scen.parameters(job.plant)['feed_axis']
    n, T = job.samples, job.period
    env = ros_environment(domain_id=domain_id)
    os.environ.update(env)
    import rclpy
    from mill_common.node_main import install_stop_handlers, make_executor, release_node
    from rclpy.signals import SignalHandlerOptions

    from mill_common import topics

    progress = Progress(quiet)
    previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    stop = install_stop_handlers()
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    graph = None
    monitor = executor = None
    try:
        monitor = _monitor(feed_axis)
        executor = make_executor()
        executor.add_node(monitor)

        def spin(timeout: float = 0.05) -> None:
            executor.spin_once(timeout_sec=timeout)
            if stop:
                raise KeyboardInterrupt
            exited = graph.exited()
            if exited:
                name, code = next(iter(exited.items()))
                raise ForceJobError(
                    f'node {name} exited with code {code} before the job ended:\n'
                    + graph.log_tail(name)
                )

        graph = Graph(scen, run_dir, env)
        # The plant last, once we hear the others: the first samples must reach us too.
        graph.launch([x for x in scen.nodes if x.name != job.plant])
        deadline = time.monotonic() + startup_timeout
        upstream = (topics.FEED_OVERRIDE, topics.REFERENCE)
        while any(monitor.count_publishers(t) < 1 for t in upstream):
            if time.monotonic() > deadline:
                missing = [t for t in upstream if monitor.count_publishers(t) < 1]
                raise ForceJobError(f'no publisher appeared on {", ".join(missing)}')
            spin()
        graph.launch([scen.node(job.plant)])
        progress.show(f'started {len(graph.procs)} processes; waiting for discovery', force=True)
        last_ns = sample_stamp_ns(n, T)  # the force after the n-th revolution
        t_start = time.monotonic()
        t_first = None
        seen, last_change = 0, t_start
        while last_ns not in monitor.force:
            spin()
            now = time.monotonic()
            if len(monitor.force) != seen:
                seen, last_change = len(monitor.force), now
                t_first = t_first or now
                progress.show(f'sample {seen - 1} / {n}')
            if now - last_change > (stall_timeout if t_first else startup_timeout):
                raise ForceJobError(
                    f'the run stalled: no force sample for {now - last_change:.0f} s '
                    f'(last: {seen - 1} of {n})'
                )
        wall = time.monotonic() - (t_first or t_start)
        # The other topics of the last samples may still be on their way.
        stamps = {sample_stamp_ns(k, T) for k in range(n)}
        settle = time.monotonic() + 5.0
        while time.monotonic() < settle and not (
            stamps <= monitor.trace_samples
            and stamps <= monitor.override.keys()
            and stamps <= monitor.state.keys()
        ):
            spin()
        graph.stop()
        progress.done()
        record = _record(monitor, job)
    finally:
        if graph is not None:
            graph.stop()
        progress.done()
        release_node(executor, monitor)
        rclpy.try_shutdown()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    design = design_of(job)
    record.j_c = continuous_cost(
        record.trace_ns,
        record.trace_force,
        job.controller_values['reference_force'],
        design.damping,
        design.omega_n,
    )
    result = ForceRunResult(scen.name, n, n * T, wall, record)
    if monitor.problems:
        sys.stderr.write('diagnostics: ' + '; '.join(sorted(set(monitor.problems))[:5]) + '\n')
    if compare_offline:
        result.offline = simulate_offline(scen)
    return result


def _record(monitor: Any, job: ForceJob) -> ForceRecord:
    n, T = job.samples, job.period
    stamps = [sample_stamp_ns(k, T) for k in range(n)]
    missing = [k for k, ns in enumerate(stamps) if ns not in monitor.override]
    missing += [k for k, ns in enumerate(stamps) if ns not in monitor.state]
    missing += [k for k, ns in enumerate(stamps) if ns not in monitor.trace_samples]
    if missing:
        raise ForceJobError(
            f'samples missing in the record: {sorted(set(missing))[:10]} (heard '
            f'{len(monitor.force)} force samples, {len(monitor.override)} overrides, '
            f'{len(monitor.state)} controller states, {len(monitor.trace_samples)} traces)'
        )
    state = np.array([monitor.state[ns] for ns in stamps])
    override = np.array([monitor.override[ns] for ns in stamps])
    end_ns = sample_stamp_ns(n, T)
    trace = sorted((p for p in monitor.trace if p[0] <= end_ns), key=lambda p: p[0])
    return ForceRecord(
        t=np.arange(n) * T,
        force=np.array([monitor.force[ns] for ns in stamps]),
        override=override[:, 0],
        slope=override[:, 1],
        beta=state[:, 4],
        feed_command=state[:, 2],
        trace_ns=np.array([p[0] for p in trace], dtype=np.int64),
        trace_force=np.array([p[1] for p in trace]),
    )


def format_result(r: ForceRunResult) -> str:
    rec = r.record
    lines = [
        f'scenario {r.scenario}: {r.samples} spindle revolutions, {r.sim_time:.3f} s of '
        f'machine time in {r.wall_time:.1f} s wall',
        f'J_c (eq. 14, from the recorded force stream) = {rec.j_c:.6g} N²·s',
        f'override: mean {np.mean(rec.override):.4f}, range [{np.min(rec.override):.4f}, '
        f'{np.max(rec.override):.4f}]; active β: '
        + ', '.join(f'{b:g}' for b in dict.fromkeys(rec.beta.tolist())),
    ]
    d = r.differences()
    if d:
        lines.append(
            f'offline: J_c = {r.offline.j_c:.6g} N²·s (relative difference '
            f'{d["j_c_relative"]:.2e}); max |distributed − offline|: force '
            f'{d["force"]:.2e} N, override {d["override"]:.2e}, β {d["beta"]:.2e}'
        )
    return '\n'.join(lines)


def format_offline(scen_name: str, rec: ForceRecord) -> str:
    return (
        f'scenario {scen_name} (offline): {len(rec.t)} spindle revolutions, J_c = '
        f'{rec.j_c:.6g} N²·s; override mean {np.mean(rec.override):.4f}; active β: '
        + ', '.join(f'{b:g}' for b in dict.fromkeys(rec.beta.tolist()))
    )


# -- windows of a recorded force-controlled run ---------------------------------------------


def state_windows(
    bag_path: str | Path, edges: Sequence[float]
) -> list[tuple[float, float, int, float, float]]:
    """(start, end, samples, mean force [N], mean override) of /mill/force_control/state
    per time window [edges[i], edges[i+1]) of a recorded run."""
    from mill_bringup.bag import joint_state_cdr, open_bag
    from mill_common import topics

    rows = []
    for _topic, _type, _log, _pub, data in open_bag(bag_path).read([topics.FORCE_CONTROL_STATE]):
        msg = joint_state_cdr(data)
        if msg is not None:
            t = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
            rows.append((t, msg.position[0], msg.position[3]))  # force, override (STATE_NAMES)
    if not rows:
        raise ForceJobError(f'{bag_path}: no {topics.FORCE_CONTROL_STATE} messages')
    data = np.array(rows)
    out = []
    for a, b in itertools.pairwise(edges):
        sel = (data[:, 0] >= a) & (data[:, 0] < b)
        n = int(np.count_nonzero(sel))
        force = float(np.mean(data[sel, 1])) if n else math.nan
        override = float(np.mean(data[sel, 2])) if n else math.nan
        out.append((a, b, n, force, override))
    return out


def main(argv: Sequence[str] | None = None) -> int:
    import argparse

    parser = argparse.ArgumentParser(
        prog='python -m mill_bringup.force_job',
        description='Mean force and feed override of a recorded force-controlled run, per '
        'time window (from /mill/force_control/state).',
    )
    parser.add_argument('bag', help='bag directory or .mcap file (run_scenario --record)')
    parser.add_argument('edges', nargs='+', type=float, help='window edges [s], increasing')
    args = parser.parse_args(argv)
    if len(args.edges) < 2 or any(b <= a for a, b in itertools.pairwise(args.edges)):
        parser.error('give at least two increasing window edges')
    try:
        windows = state_windows(args.bag, args.edges)
    except (ForceJobError, OSError, ValueError) as exc:
        print(f'force_job: error: {exc}', file=sys.stderr)
        return 1
    print('window [s]       samples   force [N]   override')
    for a, b, n, force, override in windows:
        print(f'{a:6.2f}-{b:6.2f}  {n:9d}  {force:10.1f}  {override:9.3f}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
