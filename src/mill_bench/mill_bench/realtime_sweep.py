"""Which sample rates a process layout holds on the wall clock (`benchmark --realtime`).

For each layout, the scenario runs with `--timing realtime` (the drive ticks on the wall
clock and holds the newest command) at each rate, slowest first, for a few seconds. A rate
holds when on every axis fewer than 1 % of the periods went without a fresh command, and
fewer than 1 % of the drive's ticks came more than half a period late. Both count: where
the drive shares its process with the loop (the single layout) its timer cannot fire while
the loop computes, so a slow loop delays the tick instead of missing it; the command is
then fresh at every tick, but the machine no longer keeps its sample rate. The sweep of a
layout stops at the first rate that does not hold.

Timing only: the scenario's observer and controller gains are designed for its own rate,
so at another rate an axis may trip. The drive still takes (and counts) every command, a
brake request too; the tracking is not judged here.
"""

from __future__ import annotations

import math
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from mill_bringup.cli import set_duration, set_timing
from mill_bringup.jobs.registry import job_for
from mill_bringup.runner.options import RunOptions
from mill_bringup.runner.run import run

from mill_bringup import scenario as scenario_mod

HOLDS_BELOW = 0.01  # of periods without a fresh command (worst axis), and of late ticks


@dataclass(frozen=True)
class RatePoint:
    layout: str
    rate_hz: float
    late_fraction: float  # worst axis
    latency_median_ms: float  # worst axis
    latency_p99_ms: float  # worst axis
    overruns: int  # drive ticks more than half a period late
    cpu_ms_per_tick: float
    ticks: int  # the drive's while active (the basis of overruns), else the job's

    @property
    def late_tick_fraction(self) -> float:
        return self.overruns / self.ticks if self.ticks else 1.0

    @property
    def holds(self) -> bool:
        return self.late_fraction < HOLDS_BELOW and self.late_tick_fraction < HOLDS_BELOW


def parse_rates(text: str) -> list[float]:
    """'100,250,1000' -> [100.0, 250.0, 1000.0]; ValueError naming a bad entry."""
    rates = []
    for part in text.split(','):
        try:
            rate = float(part)
        except ValueError:
            raise ValueError(f'--realtime: {part!r} is not a rate in Hz') from None
        if not math.isfinite(rate) or not 1.0 <= rate <= 10_000.0:
            raise ValueError(f'--realtime: {part} Hz is outside 1 .. 10000 Hz')
        rates.append(rate)
    return sorted(set(rates))


def measure(
    name: str, layout: str, rate: float, duration: float, run_dir: Path, domain_id: str
) -> RatePoint:
    scen = scenario_mod.load(name)
    scen.layout = layout
    set_timing(scen, 'realtime')
    set_duration(scen, duration)
    scen.add_override(f'*.sample_period={1.0 / rate!r}')
    result = run(job_for(scen), run_dir, RunOptions(quiet=True, domain_id=domain_id))
    drive = result.summary['drive'].values()
    return RatePoint(
        layout=layout,
        rate_hz=rate,
        late_fraction=max(f['late_fraction'] for f in drive),
        latency_median_ms=max(f['latency_median_ms'] for f in drive),
        latency_p99_ms=max(f['latency_p99_ms'] for f in drive),
        overruns=int(result.summary['drive_overruns']),
        cpu_ms_per_tick=result.cpu_ms_per_step,
        ticks=int(result.summary['drive_ticks']) or result.samples,
    )


def sweep(
    name: str,
    layouts: Sequence[str],
    rates: Sequence[float],
    duration: float,
    domain_id: str,
    progress=print,
) -> list[RatePoint]:
    points = []
    with tempfile.TemporaryDirectory() as tmp:
        for layout in layouts:
            for rate in sorted(rates):
                progress(f'{name}: realtime at {rate:g} Hz, layout {layout} ...')
                run_dir = Path(tmp) / f'{layout}_{rate:g}'
                point = measure(name, layout, rate, duration, run_dir, domain_id)
                points.append(point)
                if not point.holds:
                    break  # faster rates hold even less
    return points


def highest_held(points: Sequence[RatePoint], layout: str) -> float | None:
    held = [p.rate_hz for p in points if p.layout == layout and p.holds]
    return max(held) if held else None


def format_sweep(points: Sequence[RatePoint], layouts: Sequence[str]) -> list[str]:
    lines = [
        'realtime (drive on the wall clock, one sample of delay; timing only):',
        '  layout      rate    late periods   latency median   p99 [ms]   ticks late        '
        'CPU per tick',
    ]
    for p in points:
        lines.append(
            f'  {p.layout:<9} {p.rate_hz:6g} Hz   {100 * p.late_fraction:9.2f} %   '
            f'{p.latency_median_ms:13.3f}   {p.latency_p99_ms:8.3f}   {p.overruns:6d} '
            f'({100 * p.late_tick_fraction:5.2f} %)   {p.cpu_ms_per_tick:8.2f} ms'
        )
    for layout in layouts:
        best = highest_held(points, layout)
        held = f'{best:g} Hz' if best is not None else 'none of the rates tried'
        lines.append(
            f'  highest rate with < 1 % late periods and < 1 % late ticks, layout {layout}: {held}'
        )
    return lines
