"""Benchmark: speed of the 8-process lockstep job and of the transport under it.

    benchmark                    # 10 s of the slotting job + 5000 ping-pong round trips
    benchmark --duration 53.334  # the whole job

Prints steps per second and the real-time factor of the distributed job at
the scenario's sample rate, the peak RSS of every process of the graph, and,
in the same run, the round-trip rate of a plain rclpy ping-pong between two
processes (same message type, QoS and executor): the most any lockstep loop
that crosses processes could reach on this machine.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from mill_common.env import ros_environment
from mill_common.node_main import EXECUTORS

from mill_bringup import scenario as scenario_mod
from mill_bringup.runner import RunError, run


def measure_pingpong(count: int, env: dict[str, str]) -> dict:
    pong = subprocess.Popen(
        [sys.executable, '-m', 'mill_bringup.pingpong', 'pong'],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        out = subprocess.run(
            [sys.executable, '-m', 'mill_bringup.pingpong', 'ping', str(count)],
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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog='benchmark',
        description=__doc__.split('\n\n')[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument('scenario', nargs='?', default='slotting')
    parser.add_argument('--duration', type=float, default=10.0, help='machine time to run [s]')
    parser.add_argument('--round-trips', type=int, default=5000, help='ping-pong round trips')
    parser.add_argument('--executor', choices=EXECUTORS, help='rclpy executor of every node')
    parser.add_argument('--json', type=Path, help='also write the figures to this file')
    args = parser.parse_args(argv)
    if args.executor:
        os.environ['MILL_EXECUTOR'] = args.executor
    executor = os.environ.get('MILL_EXECUTOR', 'events')
    env = ros_environment()
    try:
        print(
            f'ping-pong: {args.round_trips} round trips between two processes ...', file=sys.stderr
        )
        pp = measure_pingpong(args.round_trips, env)
        scen = scenario_mod.load(args.scenario)
        for node in scen.nodes_of('mill_trajectory'):
            scen.add_override(f'{node.name}.duration={args.duration!r}')
        print(
            f'{scen.name}: {args.duration:g} s of machine time in {len(scen.nodes)} processes ...',
            file=sys.stderr,
        )
        with tempfile.TemporaryDirectory() as tmp:
            result = run(scen, Path(tmp), quiet=True, domain_id=env['ROS_DOMAIN_ID'])
    except (scenario_mod.ScenarioError, RunError, TimeoutError) as exc:
        print(f'benchmark: error: {exc}', file=sys.stderr)
        return 1
    rate = 1.0 / scen.parameters(scen.nodes_of('mill_plant')[0].name)['sample_period']
    figures = {
        'executor': executor,
        'sample_rate_hz': rate,
        'machine_time_s': result.sim_time,
        'wall_time_s': result.wall_time,
        'steps_per_second': result.steps_per_second,
        'real_time_factor': result.real_time_factor,
        'pingpong_round_trips_per_second': pp['round_trips_per_second'],
        'pingpong_median_ms': pp['median_ms'],
        'pingpong_p99_ms': pp['p99_ms'],
        'pingpong_cpu_us_per_round_trip': pp['ping_cpu_us_per_round_trip'],
        'peak_rss_mb': result.peak_rss_mb,
        'peak_rss_total_mb': sum(result.peak_rss_mb.values()),
        'cpu_count': os.cpu_count(),
    }
    rss = ', '.join(f'{k} {v:.0f}' for k, v in sorted(result.peak_rss_mb.items()))
    print(
        f'lockstep job ({len(scen.nodes)} processes, {rate:g} Hz, executor {executor}, '
        f'{os.cpu_count()} cores):\n'
        f'  {result.steps_per_second:8.0f} steps/s   real-time factor '
        f'{result.real_time_factor:.2f}   ({result.sim_time:g} s machine time in '
        f'{result.wall_time:.1f} s)\n'
        f'transport limit, rclpy ping-pong between two processes:\n'
        f'  {pp["round_trips_per_second"]:8.0f} round trips/s   median '
        f'{pp["median_ms"]:.3f} ms   p99 {pp["p99_ms"]:.3f} ms   '
        f'{pp["ping_cpu_us_per_round_trip"]:.0f} us CPU per round trip\n'
        f'peak RSS of the graph: {figures["peak_rss_total_mb"]:.0f} MB ({rss})'
    )
    if args.json:
        args.json.write_text(json.dumps(figures, indent=2))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
