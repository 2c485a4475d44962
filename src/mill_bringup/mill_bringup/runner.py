"""Scenario runner: starts every node of a scenario in its own process and reports the job.

    run_scenario slotting                      # the Beltrán 2013 job, 8 processes
    run_scenario slotting --controller pd      # the uncompensated run
    run_scenario slotting --duration 5 --compare-offline
    run_scenario slotting --record             # also write the run to a rosbag2 bag (RUN_DIR/bag)
    run_scenario rubio --variant scheme1       # one configuration of a scenario with variants
    run_scenario slotting --namespace machine2 # every topic under /machine2 (and the monitor)

The same steps for every kind of job (mill_bringup.jobs): check every variant's scenario
before anything starts; start the nodes, then, once the monitor hears them, the node that
clocks the job; follow the job with a progress bar until it is complete, stop the graph when
a node exits or nothing happens for --stall-timeout; build the record from the monitor's
messages and print the job's summary, wall time and real-time factor. Logs and
summary.json go to the run directory (--output). With --record the monitor also writes every
topic of the graph to a rosbag2 bag in MCAP storage; `report BAG` analyses it.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import math
import os
import resource
import signal
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mill_bag.errors import BagError
from mill_common.env import ros_environment
from mill_common.progress import Progress

from mill_analysis import papers
from mill_bringup.cli import add_scenario_arguments, load_scenario
from mill_bringup.graph import Graph, GraphError
from mill_bringup.jobs.base import Job, simulate
from mill_bringup.jobs.realtime import RealtimeAxisJob
from mill_bringup.jobs.registry import job_for
from mill_bringup.layout import processes
from mill_bringup.lifecycle_client import activate, deactivate
from mill_bringup.lost_samples import split_lost
from mill_bringup.scenario import Scenario, ScenarioError, check_layout
from mill_common import topics


class RunError(RuntimeError):
    """The run could not complete; str() says why."""


@dataclass
class RunResult:
    scenario: str
    kind: str
    samples: int
    sim_time: float
    wall_time: float
    real_time_factor: float
    steps_per_second: float
    cpu_ms_per_step: float
    peak_rss_mb: dict[str, float]
    cpu_ms_per_step_by_process: dict[str, float]
    peak_pss_mb: float  # graph + runner, sampled once a second (RSS counts libraries per process)
    domain_id: str
    missing_samples: dict[str, int]  # per topic, not counting lost_with_restarts
    summary: dict[str, Any]  # the job's own figures (jobs.base.Job.summary_json)
    text: str  # the job's summary as text
    problems: list[str] = field(default_factory=list)  # WARN/ERROR heard on /diagnostics
    foreign: dict[str, int] = field(default_factory=dict)  # messages left out per topic
    # samples a killed node was sending when it died, per topic (mill_bringup.lost_samples)
    lost_with_restarts: dict[str, int] = field(default_factory=dict)
    differences: dict[str, float] | None = None  # against the offline run
    bag: dict[str, Any] | None = None
    record: Any = field(default=None, repr=False)

    @property
    def intact(self) -> bool:
        """No sample missing, nothing foreign in the record or in the drive's graph."""
        owned = not any('ownership' in p for p in self.problems)
        return not self.missing_samples and not self.foreign and owned

    @property
    def offline_max_difference(self) -> float | None:
        return None if self.differences is None else max(self.differences.values(), default=0.0)

    def to_json(self) -> dict[str, Any]:
        d = {k: v for k, v in vars(self).items() if k not in ('record', 'summary', 'text')}
        d.update(self.summary)
        d['offline_max_difference'] = self.offline_max_difference
        d['total_peak_rss_mb'] = sum(self.peak_rss_mb.values())
        return d


def run(
    job: Job[Any],
    run_dir: Path,
    skip: float = 1.0,
    stall_timeout: float = 30.0,
    startup_timeout: float = 120.0,
    quiet: bool = False,
    domain_id: str | None = None,
    compare_offline: bool = False,
    record_bag: Path | None = None,
    respawn: bool = False,
    external: frozenset[str] = frozenset(),
    layout: str | None = None,
) -> RunResult:
    """Run the job across processes; the record holds samples 0 .. job.samples − 1.

    respawn: a node other than the clock node that dies is started again (at most 3 times)
    and rejoins the job, instead of ending the run.
    external: nodes of the scenario that run elsewhere (a hardware driver, a plant on
    another host): neither launched nor supervised here; an external clock node with the
    lifecycle services is activated where it would have been launched.
    layout: which nodes share a process (mill_bringup.layout; None: the scenario's). A
    clock node that is a lifecycle node (the drive) can share one: it then waits for the
    runner to activate it where it would have been launched. Another clock node keeps a
    process of its own, started last, so that it cannot start before the monitor hears the
    nodes upstream. Respawn starts a process again whose nodes are none of the clocks.
    """
    unknown = sorted(external - {n.name for n in job.scenario.nodes})
    if unknown:
        raise RunError(f'--external: scenario {job.scenario.name} has no node {unknown[0]!r}')
    scen = job.scenario
    layout = check_layout(scen.layout if layout is None else layout)
    job.prepare_graph(monitored=True)
    clock_names = {n.name for n in job.clock_nodes}
    managed = {n.name for n in job.clock_nodes if n.kind.lifecycle}
    plan = processes(scen, layout, external, alone=clock_names - managed)
    # A clock node in a container waits for `activate`, sent once the upstream is heard.
    held = [n for p in plan if p.container for n in p.nodes if n.name in clock_names]
    touched = [n for n in scen.nodes if respawn or n in held]
    given = {n.name: dict(scen.overrides.get(n.name, {})) for n in touched}  # put back at the end
    for node in held:
        scen.overrides.setdefault(node.name, {})['autostart'] = False
    if respawn:
        # A restarted node takes as long to start as any node: the plant must not give up on
        # its commands, nor its peers on its messages, before it can be back.
        for node in scen.nodes:
            name = 'lockstep_timeout' if node.name in clock_names else None
            if node.kind.per_axis:
                name = 'input_timeout'
            if name is not None:
                scen.overrides.setdefault(node.name, {}).setdefault(name, startup_timeout)
    first = [p for p in plan if p.container or not clock_names & set(p.node_names)]
    last = [p for p in plan if p not in first]
    restartable = [p.name for p in plan if not clock_names & set(p.node_names)]
    env = ros_environment(domain_id=domain_id)
    os.environ.update(env)
    import rclpy
    from mill_common.node_main import install_stop_handlers, make_executor, release_node
    from rclpy.signals import SignalHandlerOptions
    from rclpy.task import Future

    from mill_bringup.monitor import Monitor, RecordOptions

    options = None
    if record_bag is not None:
        options = RecordOptions(Path(record_bag), sim_time=job.sim_time_stamps())
    progress = Progress(job.sim_time, quiet=quiet)
    # SIGINT/SIGTERM only set a flag that the loops below turn into KeyboardInterrupt:
    # raised inside a callback of the C++ EventsExecutor it would abort the process
    # (std::terminate) and leave the graph running and the bag unclosed.
    previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    stop = install_stop_handlers()
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    graph: Graph | None = None
    monitor: Monitor | None = None
    executor = None
    bag: dict[str, Any] | None = None
    try:
        monitor = Monitor(
            job.monitor_topics(),
            options,
            job.recorded_topics(),
            namespace=scen.namespace,
            remappings=scen.remappings(),
            timed=job.timed_topics(),
        )
        executor = make_executor()
        executor.add_node(monitor)
        graph = Graph(scen, run_dir, env, respawn=restartable if respawn else ())

        clock_check = [0.0]
        peak_pss = [0.0]

        never = Future()

        def spin(when: str) -> None:
            # Take messages for 50 ms, then look at the job again. (Polling with
            # spin_once(0) costs tens of µs per call even with nothing to take.)
            executor.spin_until_future_complete(never, timeout_sec=0.05)
            if stop:
                raise KeyboardInterrupt
            if monitor.recorder is not None and monitor.recorder.error:
                raise RunError(monitor.recorder.error)
            graph.check(when)
            if time.monotonic() > clock_check[0]:
                clock_check[0] = time.monotonic() + 1.0
                peak_pss[0] = max(peak_pss[0], graph.pss())
                _check_one_clock(monitor, graph, job, env['ROS_DOMAIN_ID'], external)

        # The clock node starts last, once the monitor has matched the others' publishers:
        # it cannot see whether their messages reach the monitor.
        graph.launch(first)
        upstream = job.upstream_topics()
        deadline = time.monotonic() + startup_timeout
        while any(monitor.count_publishers(t) < 1 for t in upstream):
            if time.monotonic() > deadline:
                silent = [t for t in upstream if monitor.count_publishers(t) < 1]
                raise RunError(f'no publisher appeared on {", ".join(silent)}')
            spin('before the job started')
        graph.launch(last)
        for node in job.clock_nodes:
            # started elsewhere, perhaps waiting to be activated; or held in a container
            if node.name in external or node in held:
                activate(
                    monitor,
                    executor,
                    node.name,
                    progress,
                    started=lambda: job.progress(monitor) > -math.inf,
                    wait=startup_timeout,
                )
        progress.note(
            f'started {len(graph.procs)} processes (ROS_DOMAIN_ID={env["ROS_DOMAIN_ID"]}); '
            'waiting for discovery'
        )
        t_start = time.monotonic()
        t_first: float | None = None
        cpu_first: dict[str, float] = {}
        reached, last_change = -float('inf'), t_start
        while not job.complete(monitor):
            spin('before the job ended')
            now = time.monotonic()
            t = job.progress(monitor)
            if t > reached:
                reached, last_change = t, now
                if t_first is None:
                    t_first, cpu_first = now, graph.cpu_by_process()
            if t_first is None:
                if now - t_start > startup_timeout:
                    raise RunError(f'no step within {startup_timeout:g} s of the start')
                continue
            # A restarted process has as long to come back as any start-up takes.
            restarting = graph.last_restart is not None and now - graph.last_restart < (
                startup_timeout
            )
            limit = max(stall_timeout, startup_timeout) if restarting else stall_timeout
            if now - last_change > limit:
                raise RunError(f'the run stalled: no new sample for {limit:g} s')
            # Over the first half second the factor means nothing (one step in a microsecond).
            elapsed = now - t_first
            rtf = f'real-time factor {reached / elapsed:.2f}' if elapsed >= 0.5 else ''
            progress.update(max(reached, 0.0), rtf)
        t_end = time.monotonic()
        t_first = t_first if t_first is not None else t_start
        wall = max(t_end - t_first, 1e-9)
        started = job.started_ns()
        if started is not None:  # the job's own start (progress reports come once a second)
            wall = max((time.time_ns() - started) * 1e-9, 1e-9)
        steps = max(job.samples - 1, 1)
        cpu_by_process = {
            name: 1e3 * (used - cpu_first.get(name, 0.0)) / steps
            for name, used in graph.cpu_by_process().items()
        }
        cpu_ms_per_step = sum(cpu_by_process.values())
        settle = time.monotonic() + job.SETTLE_TIMEOUT
        while time.monotonic() < settle and not job.settled(monitor):
            spin('after the job ended')
        if job.BRAKE_AT_END:
            for node in job.clock_nodes:
                deactivate(monitor, executor, node.name, progress)
        peak = graph.peak_rss()
        peak_pss[0] = max(peak_pss[0], graph.pss())
        graph.stop()
        progress.close()
        if monitor.recorder is not None:
            # Take what the nodes sent before they stopped, then close the bag.
            drain = time.monotonic() + 0.3
            while time.monotonic() < drain:
                executor.spin_once(timeout_sec=0.05)
            monitor.close_recording()
            bag = {
                'path': str(record_bag),
                'messages': monitor.recorder.message_count,
                'size_bytes': monitor.recorder.writer.size_bytes,
            }
        record, gaps = job.record(monitor.raw)
        missing, lost = split_lost(gaps, job.owners(), graph.restarted_nodes())
        problems = graph.notes + monitor.problems()
    except GraphError as exc:
        raise RunError(str(exc)) from None
    finally:
        if graph is not None:
            graph.stop()
        if monitor is not None:
            monitor.close_recording()  # on every way out: the bag is closed and valid
        progress.close()
        release_node(executor, monitor)
        rclpy.try_shutdown()
        for name, overrides in given.items():  # the next run of the scenario may differ
            scen.overrides[name] = overrides
        for sig, handler in previous.items():
            signal.signal(sig, handler)

    peak['runner'] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    result = RunResult(
        scenario=scen.name,
        kind=job.KIND,
        samples=job.samples,
        sim_time=job.sim_time,
        wall_time=wall,
        real_time_factor=job.sim_time / wall,
        steps_per_second=job.samples / wall,
        cpu_ms_per_step=cpu_ms_per_step,
        cpu_ms_per_step_by_process=cpu_by_process,
        peak_pss_mb=peak_pss[0],
        peak_rss_mb=peak,
        domain_id=env['ROS_DOMAIN_ID'],
        missing_samples=missing,
        summary=job.summary_json(record, skip),
        text=job.summary(record, skip),
        problems=problems,
        foreign=job.foreign(record),
        lost_with_restarts=lost,
        bag=bag,
        record=record,
    )
    if bag is not None:
        sim = job.sim_time
        bag['bytes_per_sim_second'] = bag['size_bytes'] / sim if sim > 0 else None
    if compare_offline:
        result.differences = job.differences(record, simulate(job))
    return result


def _check_one_clock(
    monitor: Any, graph: Graph, job: Job[Any], domain_id: str, external: frozenset[str]
) -> None:
    """RunError when a clock other than this run's own publishes on its /clock.

    Two simulations in one domain would each step to the other's clock ticks. The check
    is repeated while the run goes on, so that two runs started together are caught too.
    An external clock node (a plant on another host) counts as this run's.
    """
    ours = sum(1 for n in job.clock_nodes if n.name in graph.node_names() or n.name in external)
    clock = monitor.resolve_topic_name(topics.CLOCK)
    found = monitor.count_publishers(clock)
    if found > ours:
        raise RunError(
            f'{clock} has {found} publishers in ROS_DOMAIN_ID={domain_id}, this run has {ours}: '
            'another simulation shares the domain; give each run its own --domain-id, or '
            'run each under its own --namespace with --private-clock'
        )


def format_result(r: RunResult) -> str:
    lines = [
        f'scenario {r.scenario}: {r.samples} samples, {r.sim_time:.3f} s of machine time',
        r.text,
        f'wall time {r.wall_time:.1f} s, real-time factor {r.real_time_factor:.2f}, '
        f'{r.steps_per_second:.0f} steps/s, {r.cpu_ms_per_step:.2f} ms CPU per step',
        f'peak RSS of the graph {sum(r.peak_rss_mb.values()):.0f} MB '
        f'({len(r.peak_rss_mb)} processes), {r.peak_pss_mb:.0f} MB in use together (PSS)',
    ]
    if r.missing_samples:
        lines.append(f'WARNING: samples missing in the record: {r.missing_samples}')
    if r.lost_with_restarts:
        lines.append(
            'note: samples lost with their killed sender (started again), not in the record: '
            f'{r.lost_with_restarts}'
        )
    if r.foreign:
        lines.append(f'ERROR: messages from other senders or malformed, left out: {r.foreign}')
    if r.problems:
        lines.append('diagnostics: ' + '; '.join(r.problems[:5]))
    if r.differences is not None:
        lines.append(
            'max |distributed - offline|: '
            + ', '.join(f'{k} {v:.3e}' for k, v in r.differences.items())
        )
    if r.bag is not None:
        per_s = r.bag['bytes_per_sim_second']
        lines.append(
            f'bag {r.bag["path"]}: {r.bag["messages"]} messages, '
            f'{r.bag["size_bytes"] / 1e6:.1f} MB'
            + (f' ({per_s / 1e6:.2f} MB per simulated second)' if per_s else '')
        )
    return '\n'.join(lines)


def _apply_namespace(
    scen: Scenario, runs: dict[str, Scenario], namespace: str | None, private_clock: bool
) -> None:
    """--namespace and --private-clock on the scenario and each of its variants."""
    for s in (scen, *runs.values()):
        if namespace is not None:
            s.set_namespace(namespace)
        s.private_clock = s.private_clock or private_clock
    if scen.private_clock and scen.namespace == topics.ROOT:
        raise ScenarioError('a private clock needs a namespace (--namespace NAME)')


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog='run_scenario',
        description='Start every node of a scenario (each in its own process, or as --layout '
        'says), run the job in '
        'lockstep and print its results.',
    )
    add_scenario_arguments(parser)
    parser.add_argument('--output', type=Path, help='run directory (default runs/NAME-TIME)')
    parser.add_argument('--domain-id', help='ROS_DOMAIN_ID (default: yours, else private)')
    parser.add_argument(
        '--stall-timeout',
        type=float,
        default=30.0,
        help='give up when no sample arrives for this long [s]; for a process that '
        '--respawn just started again, at least as long as a start-up may take',
    )
    parser.add_argument(
        '--compare-offline',
        action='store_true',
        help='also run the offline simulator and print the largest differences',
    )
    parser.add_argument(
        '--record',
        nargs='?',
        const='',
        metavar='BAG',
        help='write every topic to a rosbag2 bag (MCAP) in directory BAG, which must not '
        'exist (default: RUN_DIR/bag)',
    )
    parser.add_argument(
        '--namespace',
        metavar='NAME',
        help="run every node under this machine namespace (default: the scenario's, else /); "
        '/clock and /diagnostics stay global',
    )
    parser.add_argument(
        '--private-clock',
        action='store_true',
        help='remap the simulation clock /clock to NAMESPACE/clock, so that several '
        'simulated machines can run in one domain at the same time',
    )
    parser.add_argument('--quiet', '-q', action='store_true', help='no progress display')
    parser.add_argument(
        '--external',
        action='append',
        default=[],
        metavar='NODE',
        help='a node of the scenario that runs elsewhere, e.g. a hardware driver (repeatable)',
    )
    parser.add_argument(
        '--respawn',
        action='store_true',
        help='start a node that dies again (not the plant); it rejoins the running job (the '
        'plant and the peers then wait for a node as long as a start-up may take)',
    )
    parser.add_argument(
        '--layout',
        metavar='LAYOUT',
        help='which nodes share a process: processes (each its own), per_axis (observer and '
        "controller of an axis together), single (all in one); default: the scenario's "
        '(mill_scenario: layout:), else processes',
    )
    args = parser.parse_args(argv)
    # SIGTERM ends the run like Ctrl-C: the graph is stopped and the bag closed.
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    records: dict[str, Any] = {}
    intact = True
    try:
        scen, runs = load_scenario(args)
        if args.layout is not None:
            check_layout(args.layout)
        _apply_namespace(scen, runs, args.namespace, args.private_clock)
        jobs = {name: job_for(variant) for name, variant in runs.items()}  # all checked first
        if args.compare_offline and not all(j.HAS_OFFLINE_TWIN for j in jobs.values()):
            raise RunError('--compare-offline: a realtime run has no offline twin')
        stamp = dt.datetime.now().strftime('%Y%m%d-%H%M%S')
        run_dir = args.output or Path('runs') / f'{scen.name}-{stamp}'
        bags: dict[str, Path | None] = {}
        for name in runs:
            bags[name] = None
            if args.record is not None:
                bag = Path(args.record) if args.record else (run_dir / name) / 'bag'
                path = bag / name if name and args.record else bag
                bags[name] = path
                if path.exists():
                    raise RunError(f'--record: {path} exists already; a bag is never overwritten')
        run_dir.mkdir(parents=True, exist_ok=True)
        print(f'{scen.description}\nrun directory {run_dir}', file=sys.stderr)
        for name, job in jobs.items():
            variant_dir = run_dir / name if name else run_dir
            variant_dir.mkdir(parents=True, exist_ok=True)
            if name:
                print(f'variant {name}: {" ".join(scen.variants[name])}', file=sys.stderr)
            result = run(
                job,
                variant_dir,
                skip=args.skip,
                stall_timeout=args.stall_timeout,
                quiet=args.quiet,
                domain_id=args.domain_id,
                compare_offline=args.compare_offline,
                record_bag=bags[name],
                respawn=args.respawn,
                external=frozenset(args.external),
                layout=args.layout,
            )
            records[name] = result.record
            intact = intact and result.intact
            (variant_dir / 'summary.json').write_text(json.dumps(result.to_json(), indent=2))
            if name:
                print(f'variant {name}:')
            print(format_result(result))
    except (ScenarioError, RunError, BagError) as exc:
        print(f'run_scenario: error: {exc}', file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print('run_scenario: interrupted', file=sys.stderr)
        return 130
    text = papers.report(scen.paper, records)
    if text and any(isinstance(job, RealtimeAxisJob) for job in jobs.values()):
        text = (
            "note: a realtime run: the paper's experiment is the lockstep run at its own sample "
            "rate; these figures also depend on how this machine kept the wall clock's rate, and "
            'the verdicts below are not a reproduction (run without --timing realtime for that)\n'
        ) + text
    if text:
        print(text)
        (run_dir / 'paper.txt').write_text(text + '\n')
    if not intact:
        print(
            'run_scenario: error: the record is incomplete or foreign messages were seen '
            '(see above)',
            file=sys.stderr,
        )
        return 1
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
