"""Benchmark: how fast the offline simulator runs a scenario's job, on one core.

    python -m mill_bench.offline_speed                   # slotting, the whole job
    python -m mill_bench.offline_speed slotting --duration 10 --repeat 3

Runs the job as `offline_sim` does (mill_bringup.jobs.base.simulate: the same step objects
the nodes use), without the per-role timers of `benchmark --cores`, and prints per run the
samples, the CPU time of this process (time.process_time: on a shared machine the wall time
counts the others' work too) and the wall time, µs of CPU per sample (all axes together) and
the real-time factor (machine time over CPU time, and over wall time). The best of
`--repeat` runs is the figure to quote.
"""

from __future__ import annotations

import argparse
import sys
import time

from mill_bringup.catalogue import TRAJECTORY
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.registry import job_for

from mill_bringup import scenario as scenario_mod


def run_once(name: str, duration: float | None) -> tuple[int, float, float, float]:
    """(samples, machine time [s], CPU [s], wall [s]) of one offline run of the scenario."""
    scen = scenario_mod.load(name)
    if duration is not None:
        for node in scen.nodes_of(TRAJECTORY):
            scen.add_override(f'{node.name}.duration={duration!r}')
    job = job_for(scen)
    cpu0, wall0 = time.process_time(), time.perf_counter()
    rec = simulate(job)
    cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
    samples = len(rec.t)
    return samples, job.sim_time, cpu, wall


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog='python -m mill_bench.offline_speed',
        description='Time the offline simulator on a scenario (one core).',
    )
    parser.add_argument('scenario', nargs='?', default='slotting')
    parser.add_argument('--duration', type=float, help='machine time to run [s] (default: the job)')
    parser.add_argument('--repeat', type=int, default=1, help='runs (the best is the figure)')
    args = parser.parse_args(argv)
    best: tuple[float, float] | None = None
    for _ in range(max(1, args.repeat)):
        try:
            samples, sim_time, cpu, wall = run_once(args.scenario, args.duration)
        except scenario_mod.ScenarioError as exc:
            print(f'offline_speed: error: {exc}', file=sys.stderr)
            return 1
        us = 1e6 * cpu / max(samples, 1)
        print(
            f'{args.scenario}: {samples} samples ({sim_time:.3f} s of machine time) in '
            f'{cpu:.2f} s CPU, {wall:.2f} s wall: {us:.1f} us CPU per sample, '
            f'{sim_time / cpu:.1f}x real time on CPU ({sim_time / wall:.1f}x on the wall clock)'
        )
        if best is None or us < best[0]:
            best = (us, sim_time / cpu)
    if best is not None and args.repeat > 1:
        print(f'best: {best[0]:.1f} us CPU per sample, {best[1]:.1f}x real time')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
