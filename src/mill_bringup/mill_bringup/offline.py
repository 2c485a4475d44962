"""Offline simulator: a scenario's cores composed in one process, without ROS.

    offline_sim slotting --controller pd
    offline_sim rubio --variant scheme1
    offline_sim slotting --sweep '*_controller.adrc.omega_c=8,12,16'   # a grid, every core

It performs, sample by sample, exactly the calls the distributed graph makes (for an axis
job: plant measure -> observer correct -> controller -> plant step, observer predict), so
the two agree to floating-point precision. Every kind of job goes through the same loop
(mill_bringup.jobs.base.simulate); used for tests, parameter sweeps and as the reference of
the distributed run.
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

from mill_analysis import papers
from mill_bringup.cli import add_scenario_arguments, load_scenario, run_parameters
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.registry import job_for
from mill_bringup.scenario import ScenarioError


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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog='offline_sim',
        description='Run a scenario offline (all cores in one process, no ROS) and print '
        'its metrics.',
    )
    add_scenario_arguments(parser)
    parser.add_argument(
        '--sweep',
        action='append',
        default=[],
        metavar='NODE.NAME=V1,V2,...',
        help='run the grid of every --sweep (each point with the --param overrides, then '
        'its own) on every core and print a table of the figures (mill_bringup.sweep)',
    )
    parser.add_argument(
        '--jobs', type=int, help='--sweep: worker processes (default: one per core)'
    )
    args = parser.parse_args(argv)
    if args.sweep:
        from mill_bringup.sweep import main_sweep

        return main_sweep(args)
    records: dict[str, Any] = {}
    try:
        scen, runs = load_scenario(args)
        jobs = {name: job_for(variant) for name, variant in runs.items()}
        for name, job in jobs.items():
            t0 = time.monotonic()
            rec = records[name] = simulate(job)
            wall = time.monotonic() - t0
            if name:
                print(f'variant {name}:')
            print(job.summary(rec, args.skip).text())
            print(f'{job.sim_time:.3f} s simulated in {wall:.2f} s wall')
    except ScenarioError as exc:
        print(f'offline_sim: error: {exc}', file=sys.stderr)
        return 2
    configs = {name: job.config for name, job in jobs.items()}
    text = papers.report(scen.paper, records, run_parameters(configs))
    if text:
        print(text)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
