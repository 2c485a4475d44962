"""Which sample rates the hardware case holds in each layout (`benchmark --realtime`).

At each rate, slowest first: the floor (the drive against an echo node,
mill_bench.realtime_cases.floor), then each layout with the drive in its own process
(`hardware`), for a few seconds of the job's path each. Every rate runs in every case, so
the table is complete; the highest rate a case holds is the one below its first rate that
does not (mill_bench.realtime_figures has the criterion).

Every rate runs with the gains of the tuning rule for that rate and one sample of delay
(run_scenario --timing realtime --tuning rule), the scenario's own rate too: its gains are
designed for its rate alone, and one tuning for all keeps the rates comparable.
"""

from __future__ import annotations

import math
import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path

from mill_bringup.graph import GraphError
from mill_bringup.runner.options import RunError
from mill_bringup.scenario import ScenarioError

from mill_bench import realtime_cases
from mill_bench.drive_process import realtime_scenario
from mill_bench.realtime_figures import FLOOR, RatePoint


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
    name: str,
    case: str,
    rate: float,
    duration: float,
    run_dir: Path,
    domain_id: str,
    priority: int = 0,
) -> RatePoint:
    """One case at one rate; a run that fails is a point that does not hold, saying why."""
    # a scenario the rule cannot tune: raised
    scen = realtime_scenario(name, rate, duration, priority)
    try:
        if case == FLOOR:
            return realtime_cases.floor(scen, rate, duration, run_dir, domain_id)
        return realtime_cases.hardware(scen, case, rate, run_dir, domain_id)
    except (RunError, GraphError, ScenarioError) as exc:  # ScenarioError: the job's checks
        return RatePoint(case, rate, {}, 0, 0, notes=(f'the run failed: {exc}',))


def sweep(
    name: str,
    layouts: Sequence[str],
    rates: Sequence[float],
    duration: float,
    domain_id: str,
    progress: Callable[[str], object] = print,
    priority: int = 0,
) -> list[RatePoint]:
    """Every rate in the floor and in each layout, the cases of one rate one after the other
    (the machine's speed drifts: what is compared is measured close together)."""
    points = []
    with tempfile.TemporaryDirectory() as tmp:
        for rate in sorted(rates):
            for case in (FLOOR, *layouts):
                what = 'the floor (echo node)' if case == FLOOR else f'layout {case}'
                progress(f'{name}: realtime at {rate:g} Hz, the drive apart, {what} ...')
                run_dir = Path(tmp) / f'{case}_{rate:g}'
                point = measure(name, case, rate, duration, run_dir, domain_id, priority)
                points.append(point)
    return points
