"""What a benchmark measured (Measured), as JSON figures and as the text it prints."""

from __future__ import annotations

import os
import statistics
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from mill_bringup.catalogue import PLANT
from mill_bringup.runner.result import RunResult

from mill_bench.realtime_figures import CRITERION, FLOOR, RatePoint, highest_held
from mill_bench.realtime_text import format_sweep
from mill_bringup import scenario as scenario_mod


def _rates(values: list[float], fmt: str = '.0f') -> str:
    return ' '.join(format(v, fmt) for v in values)


def median_run(runs: list[RunResult]) -> RunResult:
    """The run of the median steps per second (the lower middle one of an even count)."""
    ordered = sorted(runs, key=lambda r: r.steps_per_second)
    return ordered[(len(ordered) - 1) // 2]


def layout_figures(result: RunResult) -> dict:
    return {
        'processes': len(result.peak_rss_mb) - 1,  # the runner is not one of the graph
        'steps_per_second': result.steps_per_second,
        'real_time_factor': result.real_time_factor,
        'wall_time_s': result.wall_time,
        'cpu_ms_per_step': result.cpu_ms_per_step,
        'cpu_ms_per_step_by_process': result.cpu_ms_per_step_by_process,
        'peak_rss_mb': result.peak_rss_mb,
        'peak_rss_total_mb': sum(result.peak_rss_mb.values()),
        'peak_pss_total_mb': result.peak_pss_mb,
    }


def floor_lines(floors: Sequence[tuple[float, float]], runs: Sequence[RunResult]) -> list[str]:
    """The floor's figures; with runs of the processes layout (one after each floor), the
    layout's share of it, run by run (median and range)."""

    def figure(values: Sequence[float], unit: str) -> str:
        spread = f' [{min(values):.0f}-{max(values):.0f}]' if len(values) > 1 else ''
        return f'{statistics.median(values):8.0f}{spread} {unit}'

    alone = [f for f, _ in floors]
    watched = [w for _, w in floors]
    out = ['empty-callback floor, the same graph in eight processes (serialized, no runner):']
    out.append(f'  {figure(alone, "steps/s")}')
    out.append(f'  {figure(watched, "steps/s")} with a ninth process reading what the runner reads')
    if runs:
        ours = [r.steps_per_second for r in runs]
        share = [100 * o / f for o, f in zip(ours, alone, strict=True)]
        share_watched = [100 * o / w for o, w in zip(ours, watched, strict=True)]
        out.append(
            f'  layout processes at {figure(share, "%").strip()} of the floor, '
            f'{figure(share_watched, "%").strip()} of the floor with the listener '
            '(each run against the floor measured just before it)'
        )
    return out


@dataclass
class Measured:
    """Everything one benchmark measured, for its figures and its text."""

    scen: scenario_mod.Scenario
    layouts: list[str]
    repeat: int
    runs: dict[str, list[RunResult]]  # per layout, in the order they ran
    pingpong: dict[str, Any] | None = None
    # (floor, floor with a listener) steps/s; paired: measured before each processes run
    floors: list[tuple[float, float]] = field(default_factory=list)
    paired: bool = False
    recording: dict[str, Any] | None = None
    sweep: list[RatePoint] = field(default_factory=list)  # realtime: floor and layouts
    sweep_load: float | None = None  # load average (1 min) as the realtime runs began

    @property
    def results(self) -> dict[str, RunResult]:
        """The median run of each layout."""
        return {name: median_run(r) for name, r in self.runs.items()}

    @property
    def sample_rate(self) -> float:
        return 1.0 / self.scen.parameters(self.scen.nodes_of(PLANT)[0].name)['sample_period']


def figures_of(m: Measured, executor: str) -> dict[str, Any]:
    """The figures as JSON (--json)."""
    result = m.results[m.layouts[0]]
    figures: dict[str, Any] = {
        'executor': executor,
        'sample_rate_hz': m.sample_rate,
        'machine_time_s': result.sim_time,
        'wall_time_s': result.wall_time,
        'steps_per_second': result.steps_per_second,
        'real_time_factor': result.real_time_factor,
        'cpu_ms_per_step': result.cpu_ms_per_step,
        'peak_rss_mb': result.peak_rss_mb,
        'peak_rss_total_mb': sum(result.peak_rss_mb.values()),
        'cpu_count': os.cpu_count(),
        'load_average_1min': os.getloadavg()[0],
        'layout': m.layouts[0],
        'layouts': {
            name: {
                **layout_figures(r),
                'steps_per_second_runs': [x.steps_per_second for x in m.runs[name]],
            }
            for name, r in m.results.items()
        },
    }
    pp = m.pingpong
    if pp is not None:
        figures.update(
            {
                'pingpong_round_trips_per_second': pp['round_trips_per_second'],
                'pingpong_median_ms': pp['median_ms'],
                'pingpong_p99_ms': pp['p99_ms'],
                'pingpong_cpu_us_per_round_trip': pp['ping_cpu_us_per_round_trip'],
            }
        )
    if m.floors:
        figures['floor_steps_per_second_runs'] = [f for f, _ in m.floors]
        figures['floor_watched_steps_per_second_runs'] = [w for _, w in m.floors]
    if m.recording is not None:
        figures['recording'] = m.recording
    if m.sweep:
        figures['realtime'] = [p.figures() for p in m.sweep]
        figures['realtime_criterion'] = CRITERION
        figures['realtime_load_average_1min'] = m.sweep_load
        figures['realtime_highest_held_hz'] = {
            name: highest_held(m.sweep, name) for name in (FLOOR, *m.layouts)
        }
    return figures


def layout_lines(m: Measured, executor: str, record: bool) -> list[str]:
    """Steps/s, real-time factor, CPU and memory of each layout."""
    lines = [f'lockstep job ({m.sample_rate:g} Hz, executor {executor}, {os.cpu_count()} cores):']
    if m.repeat > 1 and not record:
        lines.append(f'  (median of {m.repeat} runs of each layout, taken in turn; range in [])')
    for name, r in m.results.items():
        f = layout_figures(r)
        rates = [x.steps_per_second for x in m.runs[name]]
        spread = f' [{min(rates):.0f}-{max(rates):.0f}]' if len(rates) > 1 else ''
        lines.append(
            f'  layout {name:<9} {f["processes"]:2d} process{"es" if f["processes"] > 1 else "  "}'
            f'  {r.steps_per_second:6.0f}{spread} '
            f'steps/s  real-time factor {r.real_time_factor:.2f}  {r.cpu_ms_per_step:.2f} ms '
            f'CPU per step  peak RSS {f["peak_rss_total_mb"]:.0f} MB, PSS '
            f'{f["peak_pss_total_mb"]:.0f} MB  ({r.sim_time:g} s '
            f'machine time in {r.wall_time:.1f} s)'
        )
    return lines


def pingpong_lines(pp: dict[str, Any]) -> list[str]:
    return [
        'transport limit, rclpy ping-pong between two processes:',
        f'  {pp["round_trips_per_second"]:8.0f} round trips/s   median '
        f'{pp["median_ms"]:.3f} ms   p99 {pp["p99_ms"]:.3f} ms   '
        f'{pp["ping_cpu_us_per_round_trip"]:.0f} us CPU per round trip',
    ]


def process_lines(results: dict[str, RunResult]) -> list[str]:
    """Peak RSS and CPU per step of each process: one busy process bounds the rate."""
    lines = []
    for name, r in results.items():
        rss = ', '.join(f'{k} {v:.0f}' for k, v in sorted(r.peak_rss_mb.items()))
        lines.append(f'peak RSS, layout {name}: {rss} MB')
    for name, r in results.items():
        cpu = ', '.join(f'{k} {v:.2f}' for k, v in sorted(r.cpu_ms_per_step_by_process.items()))
        lines.append(f'CPU per step, layout {name}: {cpu} ms')
    return lines


def recording_lines(rec: dict[str, Any], sim_time: float) -> list[str]:
    return [
        f'recording every topic ({rec["repeat"]} runs each, alternating):',
        f'  without {_rates(rec["plain_steps_per_second"])} steps/s, median '
        f'{rec["plain_median"]:.0f}',
        f'  with    {_rates(rec["recorded_steps_per_second"])} steps/s, median '
        f'{rec["recorded_median"]:.0f}',
        f'  slowdown {rec["slowdown_percent"]:.1f} % (of the median steps/s)',
        f'  CPU per step without {_rates(rec["plain_cpu_ms_per_step"], ".2f")} ms, with '
        f'{_rates(rec["recorded_cpu_ms_per_step"], ".2f")} ms: '
        f'+{rec["cpu_increase_percent"]:.1f} % (medians; graph + runner while stepping)',
        f'  bag: {rec["bag_messages"]} messages, {rec["bag_bytes"] / 1e6:.1f} MB, '
        f'{rec["bag_bytes_per_sim_second"] / 1e6:.3f} MB per simulated second',
        f'  report on the bag ({sim_time:g} s job): {rec["report_seconds"]:.1f} s '
        f'wall, {rec["report_cpu_seconds"]:.1f} s CPU (exit code {rec["report_exit_code"]})',
    ]


def text_of(m: Measured, executor: str, record: bool, load_average: float) -> str:
    """What the benchmark prints."""
    lines = layout_lines(m, executor, record)
    if m.pingpong is not None:
        lines += pingpong_lines(m.pingpong)
    if m.floors:
        lines += floor_lines(m.floors, m.runs.get('processes', []) if m.paired else [])
    lines += process_lines(m.results)
    if m.recording is not None:
        lines += recording_lines(m.recording, m.results[m.layouts[0]].sim_time)
    if m.sweep:
        lines += format_sweep(m.sweep, m.layouts)
        if m.sweep_load is not None:
            lines.append(f'load average (1 min) as the realtime runs began: {m.sweep_load:.2f}')
    lines.append(f'load average (1 min) at the end: {load_average:.2f}')
    return '\n'.join(lines)
