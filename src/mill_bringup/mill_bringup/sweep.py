"""Batch runs of the offline simulator over a grid of parameters, on every core. ROS-free.

    offline_sim slotting --sweep '*_controller.adrc.omega_c=8,12,16' \\
        --sweep '*_observer.gpi.omega_o=500,700' --jobs 2

Each `--sweep NODE.NAME=V1,V2,...` is one axis of the grid (NODE may be a glob, as in
--param; a value may be a list: `[1, 2],[3, 4]`); every point of the grid is the scenario
with the command line's overrides, then the point's, run offline (mill_bringup.jobs.base.
simulate: the same record a distributed run gives). Points run in worker processes
(concurrent.futures.ProcessPoolExecutor), one per core by default; progress goes to stderr
as they finish, and the table of figures, one row per point (and variant) in grid order,
to stdout. A point that cannot run (a value a parameter refuses) gives its row one line
saying why; the others run on.
"""

from __future__ import annotations

import argparse
import itertools
import os
import sys
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field

from mill_analysis.summary import AxisSummary, ForceSummary, Summary

from mill_bringup.scenario import ScenarioError


@dataclass(frozen=True)
class SweepAxis:
    """One --sweep: the parameter (NODE.NAME, NODE a glob) and its values, as text."""

    name: str
    values: tuple[str, ...]


@dataclass(frozen=True)
class PointResult:
    """One grid point's figures per variant ('' the scenario itself), or why it failed."""

    index: int
    overrides: tuple[str, ...]
    figures: dict[str, dict[str, float]] = field(default_factory=dict)
    error: str = ''


def split_values(text: str) -> list[str]:
    """Comma-separated values, commas inside brackets or quotes kept (list values)."""
    out: list[str] = []
    depth, quote, start = 0, '', 0
    for i, c in enumerate(text):
        if quote:
            quote = '' if c == quote else quote
        elif c in '"\'':
            quote = c
        elif c in '[(':
            depth += 1
        elif c in '])':
            depth -= 1
        elif c == ',' and depth == 0:
            out.append(text[start:i].strip())
            start = i + 1
    out.append(text[start:].strip())
    return out


def parse_sweep(text: str) -> SweepAxis:
    """`NODE.NAME=V1,V2,...` as a SweepAxis; ScenarioError (one line) if malformed."""
    name, eq, values = text.partition('=')
    name = name.strip()
    if not eq or '.' not in name or not name.split('.', 1)[0] or not name.split('.', 1)[1]:
        raise ScenarioError(f'--sweep {text!r}: expected NODE.NAME=V1,V2,...')
    parsed = split_values(values)
    if any(not v for v in parsed):
        raise ScenarioError(f'--sweep {text!r}: an empty value')
    if len(set(parsed)) != len(parsed):
        raise ScenarioError(f'--sweep {text!r}: a value named twice')
    return SweepAxis(name, tuple(parsed))


def grid(axes: Sequence[SweepAxis]) -> list[tuple[str, ...]]:
    """Every point of the grid as its --param overrides, the last axis varying fastest."""
    names = [a.name for a in axes]
    if len(set(names)) != len(names):
        raise ScenarioError('--sweep names a parameter twice')
    return [
        tuple(f'{n}={v}' for n, v in zip(names, values, strict=True))
        for values in itertools.product(*(a.values for a in axes))
    ]


def figures(summary: Summary) -> dict[str, float]:
    """The figures a sweep's table shows of a summary (lengths in µm)."""
    if isinstance(summary, AxisSummary):
        out: dict[str, float] = {}
        for a in summary.axes:
            out[f'{a.axis} RMS e'] = 1e6 * a.rms_error
            out[f'{a.axis} max |e|'] = 1e6 * a.max_error
        if summary.contour is not None:
            out['contour RMS'] = 1e6 * summary.contour.rms_error
            out['contour max'] = 1e6 * summary.contour.max_error
        out['events'] = float(len(summary.events))
        return out
    if isinstance(summary, ForceSummary):
        return {
            'J_c': summary.j_c,
            'mean override': summary.mean_override,
            'events': float(len(summary.events)),
        }
    return {}


def run_point(args: argparse.Namespace, index: int, overrides: tuple[str, ...]) -> PointResult:
    """One grid point offline: the command line's scenario with the point's overrides last."""
    from mill_bringup.cli import load_scenario
    from mill_bringup.jobs.base import simulate
    from mill_bringup.jobs.registry import job_for

    point = argparse.Namespace(**vars(args))
    point.param = [*args.param, *overrides]
    try:
        _, runs = load_scenario(point)
        out = {}
        for name, variant in runs.items():
            job = job_for(variant)
            out[name] = figures(job.summary(simulate(job), args.skip))
    except (ScenarioError, ValueError) as exc:
        return PointResult(index, overrides, error=' '.join(str(exc).split()))
    return PointResult(index, overrides, out)


def workers(asked: int | None) -> int:
    """--jobs, or the cores this process may run on."""
    if asked is not None:
        if asked < 1:
            raise ScenarioError(f'--jobs must be >= 1, got {asked}')
        return asked
    return len(os.sched_getaffinity(0)) if hasattr(os, 'sched_getaffinity') else os.cpu_count() or 1


def run_grid(
    args: argparse.Namespace,
    points: Sequence[tuple[str, ...]],
    jobs: int,
    progress: Callable[[int, int, PointResult], None] | None = None,
) -> list[PointResult]:
    """Every point, `jobs` at a time in worker processes (in this one if jobs is 1), in
    grid order; `progress` after each point finishes."""
    results: list[PointResult] = []
    if jobs == 1:
        for i, point in enumerate(points):
            results.append(run_point(args, i, point))
            if progress is not None:
                progress(len(results), len(points), results[-1])
        return results
    with ProcessPoolExecutor(max_workers=min(jobs, len(points))) as pool:
        futures: list[Future[PointResult]] = [
            pool.submit(run_point, args, i, point) for i, point in enumerate(points)
        ]
        for done in as_completed(futures):
            results.append(done.result())
            if progress is not None:
                progress(len(results), len(points), results[-1])
    return sorted(results, key=lambda r: r.index)


def table(axes: Sequence[SweepAxis], results: Sequence[PointResult]) -> str:
    """One row per point and variant: the swept values, then the figures (or the error)."""
    columns: list[str] = []
    for r in results:
        for figs in r.figures.values():
            columns += [c for c in figs if c not in columns]
    multi = any(len(r.figures) > 1 or '' not in r.figures for r in results if r.figures)
    head = [a.name for a in axes] + (['variant'] if multi else []) + columns
    rows: list[list[str]] = []
    for r in results:
        values = [o.partition('=')[2] for o in r.overrides]
        if r.error:
            rows.append([*values, *([''] if multi else []), f'error: {r.error}'])
            continue
        for variant, figs in r.figures.items():
            cells = [f'{figs[c]:.6g}' if c in figs else '-' for c in columns]
            rows.append([*values, *([variant] if multi else []), *cells])
    widths = [len(h) for h in head]
    for row in rows:
        for j, cell in enumerate(row[: len(head)]):
            if not cell.startswith('error: '):
                widths[j] = max(widths[j], len(cell))
    lines = ['  '.join(h.rjust(w) for h, w in zip(head, widths, strict=True))]
    for row in rows:
        cells = [c.rjust(w) for c, w in zip(row, widths, strict=False)]
        lines.append('  '.join(cells + row[len(widths) :]))
    return '\n'.join(lines)


def main_sweep(args: argparse.Namespace) -> int:
    """offline_sim --sweep: the grid's table on stdout, progress on stderr; 2 for a bad
    --sweep, 1 if a point failed, else 0."""
    try:
        axes = [parse_sweep(text) for text in args.sweep]
        points = grid(axes)
        jobs = workers(args.jobs)
    except ScenarioError as exc:
        print(f'offline_sim: error: {exc}', file=sys.stderr)
        return 2

    def progress(done: int, total: int, r: PointResult) -> None:
        what = ' '.join(r.overrides)
        status = f'error: {r.error}' if r.error else 'done'
        print(f'[{done}/{total}] {what}: {status}', file=sys.stderr, flush=True)

    print(
        f'sweep: {len(points)} points on {min(jobs, len(points))} processes',
        file=sys.stderr,
        flush=True,
    )
    results = run_grid(args, points, jobs, progress)
    print('lengths in µm (RMS and max over t >= skip)' if _has_lengths(results) else '')
    print(table(axes, results))
    return 1 if any(r.error for r in results) else 0


def _has_lengths(results: Sequence[PointResult]) -> bool:
    return any('contour RMS' in f or 'x RMS e' in f for r in results for f in r.figures.values())
