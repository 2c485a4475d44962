"""Benchmark: speed of the lockstep job and of the transport under it.

    benchmark                    # 10 s of the slotting job + 5000 ping-pong round trips
    benchmark --duration 53.334  # the whole job
    benchmark --layouts processes,per_axis,single   # the same job in each process layout
    benchmark --layouts processes,single --repeat 5  # five runs of each, taken in turn
    benchmark --record --repeat 3                 # cost of recording every topic
    benchmark --layouts processes,single --realtime 100,250,500,1000   # rates each holds
    benchmark --record --duration 53.334 --repeat 1 --round-trips 0
    benchmark --cores            # the algorithm cores alone, offline, µs per call

Prints steps per second and the real-time factor of the distributed job at
the scenario's sample rate, the peak RSS of every process of the graph, and,
in the same run, the round-trip rate of a plain rclpy ping-pong between two
processes (same message type, QoS and executor): the most any lockstep loop
that crosses processes could reach on this machine.

--layout runs the nodes in another process layout (mill_bringup.layout: processes,
per_axis, single); --layouts runs the job once in each layout given, one after the other,
and prints steps per second, CPU per step and peak RSS of each. With --repeat N each layout
runs N times, the layouts taken in turn (A B A B ...) so that a machine that speeds up or
slows down during the benchmark weighs on every layout alike; the median steps per second
and the range of the N runs are printed, the other figures are those of the median run.

With --record, the job runs --repeat times without and --repeat times with
recording every topic to a rosbag2 bag (`run_scenario --record`), alternating,
and prints the slowdown of the median steps per second, the bag size per
simulated second and the time `report` takes on the last bag.

With --realtime RATES, the hardware case: at each rate, slowest first, the job runs on the
wall clock (`--timing realtime`, the tuning rule's gains for the rate) with the drive in a
process of its own and the rest of the graph in each layout, and beside it, the floor: the
same drive against an echo node that answers each state at once. Printed per case and rate:
the drive's periods without a fresh command, the most in a row, its state -> command
latency and late ticks, the CPU per tick, the latency per hop as the runner's listener took
the messages, and the highest rate each case holds with < 0.5 % of the ticks without a
fresh command, p99 latency < 1 ms, no more than 2 ticks in a row without one and < 1 %
late ticks (mill_bench.realtime_sweep).

With --cores, no ROS: the scenario runs in the offline simulator and the time spent in
each role's core (trajectory, observer, controller, plant) is printed per call: the
Python work one message triggers, against the transport's cost per message above.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from mill_bringup.catalogue import CONTROLLER, OBSERVER, TRAJECTORY
from mill_bringup.cli import set_duration
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.registry import job_for
from mill_bringup.offline import CoreTimes
from mill_bringup.runner.options import RunError, RunOptions
from mill_bringup.runner.result import RunResult
from mill_bringup.runner.run import run
from mill_common.env import ros_environment
from mill_common.node_main import EXECUTORS

from mill_bench import floor, realtime_sweep
from mill_bench.realtime_figures import CRITERION
from mill_bench.results import Measured, figures_of, text_of
from mill_bringup import scenario as scenario_mod


def measure_pingpong(count: int, env: dict[str, str]) -> dict:
    pong = subprocess.Popen(
        [sys.executable, '-m', 'mill_bench.pingpong', 'pong'],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        out = subprocess.run(
            [sys.executable, '-m', 'mill_bench.pingpong', 'ping', str(count)],
            env=env,
            capture_output=True,
            text=True,
            timeout=300,
        )
        if out.returncode != 0:
            raise RunError(f'ping-pong failed: {out.stderr.strip().splitlines()[-1:]}')
        return json.loads(out.stdout.strip().splitlines()[-1])
    finally:
        pong.kill()
        pong.wait()


def measure_recording(scen, tmp: Path, env: dict[str, str], repeat: int):
    """Runs without and with recording, alternating; the bag's size and the report's time."""
    job = job_for(scen)
    plain: list[float] = []
    recorded: list[float] = []
    plain_cpu: list[float] = []
    recorded_cpu: list[float] = []
    result: RunResult | None = None
    bag = None
    for i in range(repeat):
        order = (False, True) if i % 2 == 0 else (True, False)
        for record in order:
            run_dir = tmp / f'run{i}-{"rec" if record else "plain"}'
            bag = run_dir / 'bag' if record else bag
            print(
                f'  run {i + 1}/{repeat} {"with" if record else "without"} recording ...',
                file=sys.stderr,
            )
            options = RunOptions(
                quiet=True,
                domain_id=env['ROS_DOMAIN_ID'],
                record_bag=run_dir / 'bag' if record else None,
            )
            r = run(job, run_dir, options)
            (recorded if record else plain).append(r.steps_per_second)
            (recorded_cpu if record else plain_cpu).append(r.cpu_ms_per_step)
            if record:
                result = r
    assert result is not None and result.bag is not None, 'repeat >= 1 recorded run'
    import resource

    cpu0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    proc = subprocess.run(
        [sys.executable, '-m', 'mill_analysis.report', str(bag), '--out', str(tmp / 'report')],
        capture_output=True,
        text=True,
        timeout=600,
    )
    report_seconds = time.monotonic() - t0
    cpu1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    report_cpu = (cpu1.ru_utime - cpu0.ru_utime) + (cpu1.ru_stime - cpu0.ru_stime)
    plain_median = statistics.median(plain)
    recorded_median = statistics.median(recorded)
    figures = {
        'repeat': repeat,
        'plain_steps_per_second': plain,
        'recorded_steps_per_second': recorded,
        'plain_median': plain_median,
        'recorded_median': recorded_median,
        'slowdown_percent': 100.0 * (1.0 - recorded_median / plain_median),
        'plain_cpu_ms_per_step': plain_cpu,
        'recorded_cpu_ms_per_step': recorded_cpu,
        'cpu_increase_percent': 100.0
        * (statistics.median(recorded_cpu) / statistics.median(plain_cpu) - 1.0),
        'bag_messages': result.bag['messages'],
        'bag_bytes': result.bag['size_bytes'],
        'bag_bytes_per_sim_second': result.bag['bytes_per_sim_second'],
        'report_seconds': report_seconds,
        'report_cpu_seconds': report_cpu,
        'report_exit_code': proc.returncode,
    }
    return result, figures


def time_cores(name: str, duration: float) -> int:
    """Print the µs per call of each role's core over `duration` s of the scenario."""
    try:
        scen = scenario_mod.load(name)
        for node in scen.nodes_of(TRAJECTORY):
            scen.add_override(f'{node.name}.duration={duration!r}')
        times = CoreTimes()
        t0 = time.perf_counter()
        rec = simulate(job_for(scen), times=times)
        wall = time.perf_counter() - t0
    except scenario_mod.ScenarioError as exc:
        print(f'benchmark: error: {exc}', file=sys.stderr)
        return 1
    algorithms = {
        'observer': sorted({scen.parameters(n.name)['observer'] for n in scen.nodes_of(OBSERVER)}),
        'controller': sorted(
            {scen.parameters(n.name)['controller'] for n in scen.nodes_of(CONTROLLER)}
        ),
    }
    print(
        f'{scen.name}: the cores alone, {len(rec.t)} samples offline in {wall:.2f} s '
        f'({len(rec.t) / wall:.0f} samples/s); time per call:'
    )
    for role, us in times.per_call_us().items():
        what = ', '.join(algorithms.get(role, ()))
        print(f'  {role:<10} {us:8.2f} us   {what}')
    return 0


def layouts_of(args: argparse.Namespace, scen: scenario_mod.Scenario) -> list[str]:
    """The layouts to run, checked (ScenarioError, one line, for a bad one)."""
    if args.layouts is not None:
        names = [n.strip() for n in args.layouts.split(',')]
    else:
        names = [args.layout or scen.layout]
    for name in names:
        scenario_mod.check_layout(name)
    if len(set(names)) != len(names):
        raise scenario_mod.ScenarioError(f'--layouts names a layout twice: {args.layouts}')
    if args.record and len(names) > 1:
        raise scenario_mod.ScenarioError('--record measures one layout; give --layout')
    return names


def schedule(layouts: list[str], repeat: int) -> list[tuple[int, str]]:
    """(run index, layout) in the order they run: the layouts in turn, `repeat` rounds."""
    return [(i, name) for i in range(repeat) for name in layouts]


def measure_floor(steps: int, env: dict[str, str]) -> tuple[float, float]:
    """Steps/s of the empty-callback graph (mill_bench.floor), without and with a ninth
    process that reads what the runner reads."""
    print(f'empty-callback floor: {steps} steps in eight processes ...', file=sys.stderr)
    alone = floor.measure(steps, env)['steps_per_second']
    print('... and with a listener that reads what the runner reads', file=sys.stderr)
    return alone, floor.measure(steps, env, listener=True)['steps_per_second']


def parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog='benchmark',
        description=__doc__.split('\n\n')[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument('scenario', nargs='?', default='slotting')
    parser.add_argument('--duration', type=float, default=10.0, help='machine time to run [s]')
    parser.add_argument('--round-trips', type=int, default=5000, help='ping-pong round trips')
    parser.add_argument(
        '--floor-steps',
        type=int,
        default=3000,
        help='steps of the same graph with empty callbacks (mill_bench.floor), the floor '
        'the eight-process layout is compared with, run before each run of that layout, '
        'alone and with a ninth process reading what the runner reads; 0: not run',
    )
    parser.add_argument('--executor', choices=EXECUTORS, help='rclpy executor of every node')
    parser.add_argument('--json', type=Path, help='also write the figures to this file')
    parser.add_argument(
        '--record',
        action='store_true',
        help='measure the cost of recording every topic (runs with and without), bag size '
        'and report time',
    )
    parser.add_argument(
        '--repeat',
        type=int,
        help='runs of the job in each layout, taken in turn (default 1); with --record, '
        'runs with and without recording (default 3)',
    )
    group = parser.add_mutually_exclusive_group()
    group.add_argument(
        '--layout',
        metavar='LAYOUT',
        help="process layout of the nodes: processes, per_axis or single (default: the scenario's)",
    )
    group.add_argument(
        '--layouts',
        metavar='A,B,...',
        help='run the job once in each of these layouts, e.g. processes,per_axis,single',
    )
    parser.add_argument(
        '--realtime',
        metavar='RATES',
        help='the hardware case: also run the job on the wall clock at these sample rates '
        '[Hz], e.g. 250,500,1000, with the drive in its own process and the rest in each '
        "layout, every rate with the tuning rule's gains, and beside it the floor (the drive "
        'against an echo node); print the highest rate each holds: '
        + CRITERION.replace('%', '%%'),  # argparse formats help with %
    )
    parser.add_argument(
        '--realtime-priority',
        type=int,
        default=0,
        metavar='N',
        help='SCHED_FIFO priority of the drive and the axis nodes in the realtime runs (their '
        'realtime_priority parameter; 0: the normal scheduler)',
    )
    parser.add_argument(
        '--realtime-duration',
        type=float,
        default=3.0,
        help="seconds of the job's path in each realtime run (the floor runs as long)",
    )
    parser.add_argument(
        '--cores',
        action='store_true',
        help='time the algorithm cores alone (offline, no ROS) and print µs per call',
    )
    return parser


def measure(args: argparse.Namespace, repeat: int, env: dict[str, str]) -> Measured:
    """Ping-pong, the layouts' runs (with the floor or the recording cost), the realtime sweep."""
    scen = scenario_mod.load(args.scenario)
    layouts = layouts_of(args, scen)  # checked before anything runs
    rates = realtime_sweep.parse_rates(args.realtime) if args.realtime else []
    m = Measured(scen, layouts, repeat, {name: [] for name in layouts})
    if args.round_trips > 0:
        print(
            f'ping-pong: {args.round_trips} round trips between two processes ...', file=sys.stderr
        )
        m.pingpong = measure_pingpong(args.round_trips, env)
    # The floor is measured right before each run of the processes layout (the machine's
    # speed drifts by tens of per cent in minutes): the share is taken run by run.
    m.paired = args.floor_steps > 0 and 'processes' in layouts and not args.record
    if args.floor_steps > 0 and not m.paired:
        m.floors.append(measure_floor(args.floor_steps, env))
    set_duration(scen, args.duration)
    run_layouts(args, m, env)
    m.sweep_load = os.getloadavg()[0]  # the realtime figures depend on it, the lockstep ones not
    m.sweep = realtime_sweep.sweep(
        args.scenario,
        layouts,
        rates,
        args.realtime_duration,
        env['ROS_DOMAIN_ID'],
        progress=lambda text: print(text, file=sys.stderr),
        priority=args.realtime_priority,
    )
    return m


def run_layouts(args: argparse.Namespace, m: Measured, env: dict[str, str]) -> None:
    """The job in each layout, the layouts in turn; --record repeats inside its one layout."""
    scen = m.scen
    with tempfile.TemporaryDirectory() as tmp:
        for i, layout in schedule(m.layouts, 1 if args.record else m.repeat):
            scen.layout = layout
            which = f', run {i + 1}/{m.repeat}' if m.repeat > 1 and not args.record else ''
            print(
                f'{scen.name}: {args.duration:g} s of machine time, layout {layout}{which} ...',
                file=sys.stderr,
            )
            run_dir = Path(tmp) / f'{layout}-{i}'
            if m.paired and layout == 'processes':
                m.floors.append(measure_floor(args.floor_steps, env))
            if args.record:
                result, m.recording = measure_recording(scen, run_dir, env, m.repeat)
            else:
                options = RunOptions(quiet=True, domain_id=env['ROS_DOMAIN_ID'])
                result = run(job_for(scen), run_dir, options)
            m.runs[layout].append(result)


def main(argv: list[str] | None = None) -> int:
    cli = parser()
    args = cli.parse_args(argv)
    repeat = args.repeat if args.repeat is not None else (3 if args.record else 1)
    if repeat < 1:
        cli.error(f'--repeat must be at least 1, got {repeat}')
    if args.cores:
        return time_cores(args.scenario, args.duration)
    if args.executor:
        os.environ['MILL_EXECUTOR'] = args.executor
    executor = os.environ.get('MILL_EXECUTOR', 'events')
    env = ros_environment()
    try:
        measured = measure(args, repeat, env)
    except (scenario_mod.ScenarioError, RunError, RuntimeError, TimeoutError, ValueError) as exc:
        print(f'benchmark: error: {exc}', file=sys.stderr)
        return 1
    figures = figures_of(measured, executor)
    print(text_of(measured, executor, args.record, figures['load_average_1min']))
    if args.json:
        args.json.write_text(json.dumps(figures, indent=2))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
