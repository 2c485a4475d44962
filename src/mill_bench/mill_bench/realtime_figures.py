"""What one realtime run at one rate measured, and whether the rate holds. ROS-free.

A rate holds, for the real-time goals, when on its worst axis (the drive's own figures):

- fewer than 0.5 % of the ticks went without a fresh command,
- the p99 state -> command latency (the drive's take minus the state's stamp) is below 1 ms,
- no more than 2 ticks in a row went without a fresh command,

and fewer than 1 % of the drive's ticks came more than half a period late. The last one
counts where the drive shares its machine with a slow loop: its timer then fires late,
every command is fresh at the ticks that do come, and yet the sample rate is not kept.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

FLOOR = 'floor'  # the case of the same drive against an echo node

NO_COMMAND_BELOW = 0.005  # of the ticks, worst axis
P99_BELOW_MS = 1.0
RUN_AT_MOST = 2  # ticks in a row without a fresh command
LATE_TICKS_BELOW = 0.01
CRITERION = (
    '< 0.5 % of the ticks without a fresh command, p99 state->command latency < 1 ms, '
    'no more than 2 ticks in a row without a fresh command (worst axis, as the drive '
    'counts them), and < 1 % of the ticks more than half a period late'
)


def worst(values: Iterable[float]) -> float:
    """The largest; NaN if any is NaN or there is none (a figure the drive could not give)."""
    values = list(values)
    if not values or any(math.isnan(v) for v in values):
        return math.nan
    return max(values)


@dataclass(frozen=True)
class RatePoint:
    case: str  # a process layout, or FLOOR
    rate_hz: float
    # per axis, the drive's figures (mill_bringup.jobs.realtime.DRIVE_FIGURES)
    drive: Mapping[str, Mapping[str, float]]
    overruns: int  # drive ticks more than half a period late
    ticks: int  # the drive's ticks while active, the basis of overruns
    # per axis and hop (mill_bench.hops): median and p99 [ms] at the listener
    hops: Mapping[str, Mapping[str, tuple[float, float]]] = field(default_factory=dict)
    cpu_drive_ms: float = math.nan  # per tick, the drive's process
    cpu_rest_ms: float = math.nan  # per tick, the rest: graph + runner, or echo + listener
    notes: tuple[str, ...] = ()  # what went wrong in the run (a trip, a brake, an error)

    def _worst(self, figure: str) -> float:
        return worst(f.get(figure, math.nan) for f in self.drive.values())

    @property
    def late_fraction(self) -> float:
        return self._worst('late_fraction')

    @property
    def longest_late_run(self) -> float:
        return self._worst('longest_late_run')

    @property
    def latency_median_ms(self) -> float:
        return self._worst('latency_median_ms')

    @property
    def latency_p99_ms(self) -> float:
        return self._worst('latency_p99_ms')

    @property
    def late_tick_fraction(self) -> float:
        return self.overruns / self.ticks if self.ticks else math.nan

    def failed(self) -> list[str]:
        """The parts of the criterion this run misses, by short names (none: it holds)."""
        met = {
            'no command': self.late_fraction < NO_COMMAND_BELOW,
            'p99': self.latency_p99_ms < P99_BELOW_MS,
            'in a row': self.longest_late_run <= RUN_AT_MOST,
            'late ticks': self.late_tick_fraction < LATE_TICKS_BELOW,
        }
        return [name for name, ok in met.items() if not ok]  # NaN compares False: missed

    @property
    def holds(self) -> bool:
        return not self.failed()

    def figures(self) -> dict[str, Any]:
        """As JSON: every field, the worst-axis figures and the verdict."""
        return {
            **asdict(self),
            'late_fraction': self.late_fraction,
            'longest_late_run': self.longest_late_run,
            'latency_median_ms': self.latency_median_ms,
            'latency_p99_ms': self.latency_p99_ms,
            'late_tick_fraction': self.late_tick_fraction,
            'failed': self.failed(),
            'holds': self.holds,
        }


def highest_held(points: Iterable[RatePoint], case: str) -> float | None:
    """The highest rate of a case below the first that does not hold (a faster rate that
    happens to hold above one that failed is luck, not a rate this machine keeps)."""
    best = None
    for p in sorted((p for p in points if p.case == case), key=lambda p: p.rate_hz):
        if not p.holds:
            break
        best = p.rate_hz
    return best


def first_failed(points: Iterable[RatePoint], case: str) -> RatePoint | None:
    """The slowest rate of a case that does not hold."""
    failed = [p for p in points if p.case == case and not p.holds]
    return min(failed, key=lambda p: p.rate_hz) if failed else None
