"""The text of `benchmark --realtime`: the cases per rate, the latency per hop, the verdicts."""

from __future__ import annotations

from collections.abc import Sequence

from mill_bench.hops import HOPS
from mill_bench.realtime_figures import (
    CRITERION,
    FLOOR,
    RatePoint,
    first_failed,
    highest_held,
)

HEADER = (
    'realtime, the hardware case: the drive (plant_node, timing realtime) in its own process, '
    'the rest of the graph in each layout, the runner activating the drive (run_scenario '
    '--external plant); floor: the same drive at the same rate against an echo node that '
    'answers each state at once, with the same listener. One sample of delay; every rate '
    "with the tuning rule's gains for it (--tuning rule), not the scenario's own."
)
HOPS_HEADER = (
    'latency per hop [ms], median / p99 per axis, as one listener took the messages (the '
    "runner's monitor; for the floor the same monitor), all on this machine's system clock: "
    "state = the state's arrival minus its stamp (the drive's acquisition time, taken before "
    'it integrates and publishes); observer = estimate minus state, controller = command '
    'minus estimate, loop = command minus state, each a difference of arrival times at the '
    'listener. No publish times are taken: a hop includes the difference of the two '
    "messages' delivery to the listener."
)


def _pair(values: tuple[float, float] | None) -> str:
    return '-' if values is None else f'{values[0]:.3f} / {values[1]:.3f}'


def _verdict(p: RatePoint) -> str:
    return 'yes' if p.holds else 'no: ' + ', '.join(p.failed())


def case_lines(points: Sequence[RatePoint]) -> list[str]:
    """One line per case and rate: the drive's figures (worst axis) and the CPU per tick."""
    lines = [
        f'  {"case":<10}{"rate":>8}   no fresh command   in a row   drive latency [ms]: '
        'median     p99   ticks late              CPU/tick [ms]: drive   rest   holds'
    ]
    for p in points:
        ticks = f'{p.overruns} of {p.ticks} ({100 * p.late_tick_fraction:.2f} %)'
        lines.append(
            f'  {p.case:<10}{p.rate_hz:5g} Hz   {100 * p.late_fraction:14.2f} %   '
            f'{p.longest_late_run:8.0f}   {p.latency_median_ms:25.3f} {p.latency_p99_ms:7.3f}'
            f'   {ticks:<22}  {p.cpu_drive_ms:19.3f} {p.cpu_rest_ms:6.3f}   {_verdict(p)}'
        )
    for p in points:
        lines += [f'  {p.case} {p.rate_hz:g} Hz: {note}' for note in p.notes]
    return lines


def hop_lines(points: Sequence[RatePoint]) -> list[str]:
    """Per case, rate and axis: median / p99 of each hop."""
    lines = [f'  {"case":<10}{"rate":>8}  axis' + ''.join(f'{hop:>17}' for hop in HOPS)]
    for p in points:
        for axis, per_hop in p.hops.items():
            cells = ''.join(f'{_pair(per_hop.get(hop)):>17}' for hop in HOPS)
            lines.append(f'  {p.case:<10}{p.rate_hz:5g} Hz  {axis:>4}{cells}')
    return lines


def verdict_lines(points: Sequence[RatePoint], layouts: Sequence[str]) -> list[str]:
    """Per case, the highest rate that holds, and what the next one missed."""
    lines = []
    for case in (FLOOR, *layouts):
        best = highest_held(points, case)
        text = f'{best:g} Hz' if best is not None else 'none of the rates tried'
        failed = first_failed(points, case)
        if failed is not None:
            text += f' ({failed.rate_hz:g} Hz missed: {", ".join(failed.failed())})'
        lines.append(f'  {case}: {text}')
    return lines


def format_sweep(points: Sequence[RatePoint], layouts: Sequence[str]) -> list[str]:
    lines = [HEADER, f'a rate holds with {CRITERION}:']
    lines += case_lines(points)
    if any(p.hops for p in points):
        lines += [HOPS_HEADER, *hop_lines(points)]
    lines.append('highest rate that holds (below the first that does not):')
    return lines + verdict_lines(points, layouts)
