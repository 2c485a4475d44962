"""Scenario runner: starts every node of a scenario in its own process and reports the job.

    run_scenario slotting                      # the Beltrán 2013 job, 8 processes
    run_scenario slotting --controller pd      # the uncompensated run
    run_scenario slotting --duration 5 --compare-offline
    run_scenario slotting --record             # also write the run to a rosbag2 bag (RUN_DIR/bag)

Each node runs as `ros2 run` would start it (`--ros-args -r __node:=NAME
--params-file SCENARIO`). The runner listens to the run, shows progress, stops
the graph when the trajectory reports the job done, and prints per-axis
tracking and disturbance-estimation errors, wall time and real-time factor.
Logs and summary.json go to the run directory (--output). With --record the
monitor also writes every topic of the graph to a rosbag2 bag in MCAP storage
(see mill_bag.recorder); `report BAG` analyses it.
"""

from __future__ import annotations

import argparse
import datetime as dt
import importlib.metadata
import json
import os
import signal
import subprocess
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import yaml
from mill_bag.errors import BagError
from mill_common.env import ros_environment
from mill_common.timebase import period_ns, seconds
from mill_trajectory.config import build_job

from mill_bringup import force_job, papers
from mill_bringup import scenario as scenario_mod
from mill_bringup.metrics import AxisMetrics, RunRecord, format_summary, summarize
from mill_bringup.offline import (
    apply_cli_overrides,
    build_axis_cores,
    job_steps,
    simulate,
    variants,
)

JOB_STATUS = 'mill_trajectory: job'
PLANT_STATUS = 'mill_plant: lockstep'


class RunError(RuntimeError):
    """The run could not complete; str() says why."""


@dataclass
class RunResult:
    scenario: str
    samples: int
    sim_time: float
    wall_time: float
    real_time_factor: float
    steps_per_second: float
    metrics: list[AxisMetrics]
    missing_samples: dict[str, int]
    peak_rss_mb: dict[str, float]
    domain_id: str
    cpu_ms_per_step: float | None = None  # CPU time of graph + runner per step while stepping
    offline_max_difference: float | None = None
    bag: dict | None = None
    record: RunRecord | None = field(default=None, repr=False)

    def to_json(self) -> dict:
        d = asdict(self)
        d.pop('record')
        d['total_peak_rss_mb'] = sum(self.peak_rss_mb.values())
        return d


def module_of(package: str, executable: str) -> str:
    """The Python module behind a package's console script (what `ros2 run` would start)."""
    for ep in importlib.metadata.entry_points(group='console_scripts'):
        if ep.name == executable and ep.value.startswith(package + '.'):
            return ep.value.split(':')[0]
    raise scenario_mod.ScenarioError(f'{package} has no executable {executable!r}')


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of a live process [s] (/proc/PID/stat), 0 if unreadable."""
    try:
        fields = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')
    except (OSError, IndexError, ValueError):
        return 0.0


def vm_hwm_mb(pid: int) -> float:
    """Peak resident memory of a live process [MB] (VmHWM), NaN if unreadable."""
    try:
        for line in Path(f'/proc/{pid}/status').read_text().splitlines():
            if line.startswith('VmHWM:'):
                return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return float('nan')


class Graph:
    """The scenario's node processes."""

    def __init__(self, scen: scenario_mod.Scenario, run_dir: Path, env: dict[str, str]) -> None:
        self.scen = scen
        self.procs: dict[str, subprocess.Popen] = {}
        self.logs: dict[str, Path] = {}
        log_dir = run_dir / 'logs'
        log_dir.mkdir(parents=True, exist_ok=True)
        overrides = run_dir / 'overrides.yaml'
        overrides.write_text(
            yaml.safe_dump({n: {'ros__parameters': p} for n, p in scen.overrides.items()})
        )
        self._log_dir = log_dir
        self._overrides = overrides
        self._env = env

    def launch(self, nodes) -> None:
        """Start these nodes of the scenario, each in its own process."""
        for node in nodes:
            cmd = [
                sys.executable,
                '-m',
                module_of(node.package, node.executable),
                '--ros-args',
                '-r',
                f'__node:={node.name}',
                '--params-file',
                str(self.scen.path),
                '--params-file',
                str(self._overrides),
            ]
            self.logs[node.name] = self._log_dir / f'{node.name}.log'
            with open(self.logs[node.name], 'w') as log:
                self.procs[node.name] = subprocess.Popen(
                    cmd,
                    stdout=log,
                    stderr=subprocess.STDOUT,
                    env=self._env,
                    start_new_session=True,
                )

    def exited(self) -> dict[str, int]:
        return {n: p.returncode for n, p in self.procs.items() if p.poll() is not None}

    def cpu(self) -> float:
        """CPU seconds used so far by the node processes and this process."""
        return time.process_time() + sum(cpu_seconds(p.pid) for p in self.procs.values())

    def peak_rss(self) -> dict[str, float]:
        return {n: vm_hwm_mb(p.pid) for n, p in self.procs.items() if p.poll() is None}

    def log_tail(self, name: str, lines: int = 6) -> str:
        try:
            text = self.logs[name].read_text().strip().splitlines()
        except OSError:
            return ''
        return '\n'.join('    ' + t for t in text[-lines:])

    def stop(self, grace: float = 5.0) -> None:
        for p in self.procs.values():
            if p.poll() is None:
                p.send_signal(signal.SIGINT)
        deadline = time.monotonic() + grace
        for p in self.procs.values():
            try:
                p.wait(max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()


class Progress:
    def __init__(self, quiet: bool) -> None:
        self.quiet = quiet
        self.tty = sys.stderr.isatty()
        self.next = 0.0

    def show(self, text: str, force: bool = False) -> None:
        now = time.monotonic()
        if self.quiet or (now < self.next and not force):
            return
        self.next = now + (0.5 if self.tty else 5.0)
        sys.stderr.write(('\r' + text + '   ') if self.tty else text + '\n')
        sys.stderr.flush()

    def done(self) -> None:
        if self.tty and not self.quiet:
            sys.stderr.write('\n')


def run(
    scen: scenario_mod.Scenario,
    run_dir: Path,
    skip: float = 1.0,
    stall_timeout: float = 30.0,
    startup_timeout: float = 120.0,
    quiet: bool = False,
    domain_id: str | None = None,
    compare_offline: bool = False,
    record_bag: Path | None = None,
) -> RunResult:
    # Validate every node's parameters, and that the axes' cores fit, before starting anything.
    for node in scen.nodes:
        scen.parameters(node.name)
    build_axis_cores(scen)
    # The runner's monitor listens to every state topic too: the plant waits for it
    # (controller, observer, monitor), so the first samples reach the record.
    for node in scen.nodes_of('mill_plant'):
        scen.overrides.setdefault(node.name, {}).setdefault('min_subscribers', 3)
    plant_values = scen.parameters(scen.nodes_of('mill_plant')[0].name)
    dt_ns = period_ns(plant_values['sample_period'])
    job = build_job(scen.parameters(scen.nodes_of('mill_trajectory')[0].name))
    n = job_steps(job.end_time, dt_ns)
    axes = list(plant_values['axes'])

    env = ros_environment(domain_id=domain_id)
    os.environ.update(env)
    import rclpy
    from mill_common.node_main import install_stop_handlers, make_executor, release_node
    from rclpy.signals import SignalHandlerOptions

    from mill_bringup.monitor import Monitor, RecordOptions, plant_status

    options = None
    if record_bag is not None:
        # The graph's clock: nodes with use_sim_time stamp in sim time (the plant's k T).
        trajectory = scen.nodes_of('mill_trajectory')[0].name
        sim_time = bool(scen.raw_parameters(trajectory).get('use_sim_time', False))
        options = RecordOptions(Path(record_bag), sim_time=sim_time)
    progress = Progress(quiet)
    # SIGINT/SIGTERM only set a flag that the loops below turn into KeyboardInterrupt:
    # raised inside a callback of the C++ EventsExecutor it would abort the process
    # (std::terminate) and leave the graph running and the bag unclosed.
    previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    stop = install_stop_handlers()
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    graph = None
    monitor = None
    executor = None
    bag = None

    def spin() -> None:
        executor.spin_once(timeout_sec=0.05)
        if stop:
            raise KeyboardInterrupt

    try:
        monitor = Monitor(axes, record=options)
        executor = make_executor()
        executor.add_node(monitor)
        graph = Graph(scen, run_dir, env)
        # The plant starts last, once this monitor has matched the other nodes'
        # publishers: the plant cannot see whether an observer's estimates reach
        # the monitor, and estimates sent before that match would be lost.
        plants = scen.nodes_of('mill_plant')
        graph.launch([n for n in scen.nodes if n not in plants])
        upstream = [f'/mill/{a}/estimate' for a in axes] + ['/mill/reference']
        deadline = time.monotonic() + startup_timeout
        while any(monitor.count_publishers(t) < 1 for t in upstream):
            if time.monotonic() > deadline:
                missing = [t for t in upstream if monitor.count_publishers(t) < 1]
                raise RunError(f'no publisher appeared on {", ".join(missing)}')
            exited = graph.exited()
            if exited:
                name, code = next(iter(exited.items()))
                raise RunError(
                    f'node {name} exited with code {code} before the job started:\n'
                    + graph.log_tail(name)
                )
            executor.spin_once(timeout_sec=0.05)
        graph.launch(plants)
        progress.show(
            f'started {len(graph.procs)} processes (ROS_DOMAIN_ID={env["ROS_DOMAIN_ID"]}); '
            f'waiting for discovery',
            force=True,
        )
        t_start = time.monotonic()
        t_first = None
        last_count, last_change = 0, t_start
        state_topic = f'/mill/{axes[0]}/state'
        counts_needed = [f'/mill/{a}/{kind}' for a in axes for kind in ('state', 'estimate')]
        while True:
            spin()
            now = time.monotonic()
            exited = graph.exited()
            if exited:
                name, code = next(iter(exited.items()))
                raise RunError(
                    f'node {name} exited with code {code} before the job ended:\n'
                    + graph.log_tail(name)
                )
            if monitor.recorder is not None and monitor.recorder.error:
                raise RunError(monitor.recorder.error)
            count = monitor.count(state_topic)
            if count != last_count:
                last_count, last_change = count, now
                if t_first is None:
                    t_first = now
                    cpu_first = graph.cpu()
            if t_first is None and now - t_start > startup_timeout:
                raise RunError(f'no step within {startup_timeout:g} s of the start')
            if t_first is not None and now - last_change > stall_timeout:
                raise RunError(f'the run stalled: no new sample for {stall_timeout:g} s')
            last_ns = (n - 1) * dt_ns
            if all(monitor.latest_stamp_ns(t) >= last_ns for t in counts_needed):
                break
            if t_first is not None:
                t_sim = seconds(max(monitor.last_stamp_ns, 0))
                rtf = t_sim / max(now - t_first, 1e-9)
                progress.show(
                    f't = {t_sim:7.2f} / {job.end_time:.2f} s '
                    f'({100 * t_sim / job.end_time:5.1f} %), real-time factor {rtf:.2f}'
                )
        wall = time.monotonic() - t_first
        cpu_ms_per_step = 1e3 * (graph.cpu() - cpu_first) / max(n - 1, 1)
        # Let the last ground-truth and force messages of the final step arrive.
        settle = time.monotonic() + 1.0
        while time.monotonic() < settle:
            spin()
        peak = graph.peak_rss()
        status = plant_status(monitor.diagnostics, PLANT_STATUS)
        graph.stop()
        progress.done()
        if monitor.recorder is not None:
            # Take what the nodes sent before they stopped, then close the bag.
            drain = time.monotonic() + 0.3
            while time.monotonic() < drain:
                spin()
            monitor.close_recording()
            bag = {
                'path': str(record_bag),
                'messages': monitor.recorder.message_count,
                'size_bytes': monitor.recorder.writer.size_bytes,
            }
        record, missing = monitor.record(n, dt_ns)
    finally:
        if graph is not None:
            graph.stop()
        if monitor is not None:
            monitor.close_recording()  # on every way out: the bag is closed and valid
        progress.done()
        release_node(executor, monitor)
        rclpy.try_shutdown()
        for sig, handler in previous.items():
            signal.signal(sig, handler)

    import resource

    peak['runner'] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    sim_time = seconds((n - 1) * dt_ns)
    result = RunResult(
        scenario=scen.name,
        samples=n,
        sim_time=sim_time,
        wall_time=wall,
        real_time_factor=sim_time / wall,
        steps_per_second=n / wall,
        metrics=summarize(record, skip),
        missing_samples={k: v for k, v in missing.items() if v},
        peak_rss_mb=peak,
        domain_id=env['ROS_DOMAIN_ID'],
        cpu_ms_per_step=cpu_ms_per_step,
        bag=bag,
        record=record,
    )
    if bag is not None:
        bag['bytes_per_sim_second'] = bag['size_bytes'] / sim_time if sim_time > 0 else None
    faults = {k: v for k, v in status.items() if k.endswith('.faults') and v != '0'}
    if faults:
        sys.stderr.write(f'plant braked axes on non-finite commands (steps): {faults}\n')
    if compare_offline:
        offline = simulate(scen)
        result.offline_max_difference = max_difference(record, offline)
    return result


def max_difference(a: RunRecord, b: RunRecord) -> float:
    """Largest |tracking error a - b| over all samples and axes; inf where only one has a value."""
    ea, eb = a.tracking_error, b.tracking_error
    if ea.shape != eb.shape:
        return float('inf')
    diff = np.abs(ea - eb)
    same_gap = np.isnan(ea) & np.isnan(eb)
    diff[same_gap] = 0.0
    diff[np.isnan(diff)] = np.inf
    return float(diff.max())


def format_result(r: RunResult, skip: float) -> str:
    lines = [
        f'scenario {r.scenario}: {r.samples} samples, {r.sim_time:.3f} s of machine time',
        format_summary(r.metrics, skip),
        f'wall time {r.wall_time:.1f} s, real-time factor {r.real_time_factor:.2f}, '
        f'{r.steps_per_second:.0f} steps/s, {r.cpu_ms_per_step:.2f} ms CPU per step',
        f'peak RSS of the graph {sum(r.peak_rss_mb.values()):.0f} MB '
        f'({len(r.peak_rss_mb)} processes)',
    ]
    if r.missing_samples:
        lines.append(f'WARNING: samples missing in the record: {r.missing_samples}')
    if r.offline_max_difference is not None:
        lines.append(f'max |e_distributed - e_offline| = {r.offline_max_difference:.3e} m')
    if r.bag is not None:
        per_s = r.bag['bytes_per_sim_second']
        lines.append(
            f'bag {r.bag["path"]}: {r.bag["messages"]} messages, '
            f'{r.bag["size_bytes"] / 1e6:.1f} MB'
            + (f' ({per_s / 1e6:.2f} MB per simulated second)' if per_s else '')
        )
    return '\n'.join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog='run_scenario',
        description='Start every node of a scenario in its own process, run the job in '
        'lockstep and print its results.',
    )
    parser.add_argument('scenario', nargs='?', default='slotting', help='name or YAML file')
    parser.add_argument(
        '--param',
        '-p',
        action='append',
        default=[],
        metavar='NODE.NAME=VALUE',
        help='override a node parameter; NODE may be a glob',
    )
    parser.add_argument('--controller', help='shortcut for -p "*_controller.controller=NAME"')
    parser.add_argument('--duration', type=float, help='end the job after this time [s]')
    parser.add_argument(
        '--skip',
        type=float,
        default=1.0,
        help='metrics over t >= SKIP (start transient excluded) [s]',
    )
    parser.add_argument('--output', type=Path, help='run directory (default runs/NAME-TIME)')
    parser.add_argument('--domain-id', help='ROS_DOMAIN_ID (default: yours, else private)')
    parser.add_argument(
        '--stall-timeout',
        type=float,
        default=30.0,
        help='give up when no sample arrives for this long [s]',
    )
    parser.add_argument(
        '--compare-offline',
        action='store_true',
        help='also run the offline simulator and print the largest difference',
    )
    parser.add_argument(
        '--record',
        nargs='?',
        const='',
        metavar='BAG',
        help='write every topic to a rosbag2 bag (MCAP) in directory BAG, which must not '
        'exist (default: RUN_DIR/bag)',
    )
    parser.add_argument('--quiet', '-q', action='store_true', help='no progress line')
    parser.add_argument(
        '--variant', help="run only this one of the scenario's variants (default: all of them)"
    )
    args = parser.parse_args(argv)
    # SIGTERM ends the run like Ctrl-C: the graph is stopped and the bag closed.
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    try:
        scen = scenario_mod.load(args.scenario)
        apply_cli_overrides(scen, args)
        stamp = dt.datetime.now().strftime('%Y%m%d-%H%M%S')
        run_dir = args.output or Path('runs') / f'{scen.name}-{stamp}'
        run_dir.mkdir(parents=True, exist_ok=True)
        runs = variants(scen, args.variant)
        bags: dict[str, Path | None] = {}
        for name in runs:
            bags[name] = None
            if args.record is not None:
                bag = Path(args.record) if args.record else (run_dir / name) / 'bag'
                bags[name] = bag / name if name and args.record else bag
                if bags[name].exists():
                    raise RunError(
                        f'--record: {bags[name]} exists already; a bag is never overwritten'
                    )
        print(f'{scen.description}\nrun directory {run_dir}', file=sys.stderr)
        records = {}
        for name, variant in runs.items():
            variant_dir = run_dir / name if name else run_dir
            variant_dir.mkdir(parents=True, exist_ok=True)
            record_bag = bags[name]
            if name:
                print(f'variant {name}: {" ".join(scen.variants[name])}', file=sys.stderr)
            if force_job.is_force_job(variant):
                if record_bag is not None:
                    raise RunError(
                        '--record is not available for a force job yet: start the `recorder` '
                        'node beside it'
                    )
                forced = force_job.run(
                    variant,
                    variant_dir,
                    quiet=args.quiet,
                    domain_id=args.domain_id,
                    compare_offline=args.compare_offline,
                    stall_timeout=args.stall_timeout,
                )
                (variant_dir / 'summary.json').write_text(json.dumps(forced.to_json(), indent=2))
                print(force_job.format_result(forced))
                continue
            result = run(
                variant,
                variant_dir,
                skip=args.skip,
                stall_timeout=args.stall_timeout,
                quiet=args.quiet,
                domain_id=args.domain_id,
                compare_offline=args.compare_offline,
                record_bag=record_bag,
            )
            records[name] = result.record
            (variant_dir / 'summary.json').write_text(json.dumps(result.to_json(), indent=2))
            if name:
                print(f'variant {name}:')
            print(format_result(result, args.skip))
    except (scenario_mod.ScenarioError, RunError, BagError, force_job.ForceJobError) as exc:
        print(f'run_scenario: error: {exc}', file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print('run_scenario: interrupted', file=sys.stderr)
        return 130
    text = papers.report(scen.paper, records)
    if text:
        print(text)
        (run_dir / 'paper.txt').write_text(text + '\n')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
