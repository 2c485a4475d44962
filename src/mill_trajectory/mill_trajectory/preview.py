"""gcode-preview: a part program's path, time, extents, pauses and messages before anything moves.

    gcode-preview part.ngc [--output part.png] [-p gcode.start=[-0.075,-0.105,-0.005] ...]

The program is read, checked against the travel and planned exactly as the trajectory node
does (`trajectory: gcode`, mill_trajectory.config.build_job), with the trajectory's
parameters at their defaults unless `-p NAME=VALUE` (a YAML value, as in a scenario file)
says otherwise. It prints:

- the machine time of the plan (the pauses' time at rest not included: an operator's, or
  gcode.resume_after each);
- per axis the extents of the planned path against the machine's travel (travel.min,
  travel.max), and the room left on each side;
- every pause (M0, M1), tool change and message ((MSG, …), (DEBUG, …), (PRINT, …)) with its
  line and the machine time at which it comes;

and draws the programmed path (rapids dashed, feed moves solid, arcs as their chords) in
XY, XZ and 3D, with the pauses and tool changes marked, into a PNG (matplotlib, Agg). A
program that cannot run is refused in one line, `file:line:column: what`, as the reader
says it, and nothing is drawn (exit code 1; 2: usage).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import yaml
from mill_common.executable import release_stop_signals
from mill_common.parameters import ParameterError, validate

from mill_trajectory.config import TravelParams, build_job, parameter_specs
from mill_trajectory.gcode_program import GcodeTrajectory
from mill_trajectory.gcode_words import GcodeError, Move
from mill_trajectory.hold import MESSAGE, PAUSE, TOOL_CHANGE, ProgramEvent
from mill_trajectory.toolpath import arc_points

MAX_SAMPLES = 200_000  # the planned path is sampled at 1 ms, or coarser beyond this many


def values_of(program: str, given: Sequence[str]) -> dict[str, Any]:
    """The trajectory's parameters for this program: defaults, then NAME=VALUE (YAML)."""
    specs = dict(parameter_specs())
    raw: dict[str, Any] = {name: spec.default for name, spec in specs.items()}
    raw.update({'trajectory': 'gcode', 'gcode.file': program})
    for text in given:
        name, sep, value = text.partition('=')
        if not sep or name not in specs:
            raise ValueError(f'-p {text}: give NAME=VALUE with a trajectory parameter NAME')
        raw[name] = yaml.safe_load(value)
    return {name: validate(specs[name], value, name) for name, value in raw.items()}


def extents(path: GcodeTrajectory, step: float) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Lowest and highest x, y, z of the planned path, sampled every `step` [s]."""
    lo, hi = path.bounds(step)
    return lo, hi


def sample_step(path: GcodeTrajectory) -> float:
    return max(1e-3, path.end_time / MAX_SAMPLES)


def report(path: GcodeTrajectory, values: dict[str, Any]) -> list[str]:
    """The lines gcode-preview prints."""
    travel = TravelParams.from_node_values(values)
    lo, hi = extents(path, sample_step(path))
    pauses = [e for e in path.events if e.kind == PAUSE]
    lines = [f'machine time {path.end_time:.3f} s (planned; {path.feed_summary})']
    if pauses:
        after = path.resume_after
        waits = (
            f'plus {len(pauses)} x {after:g} s at rest (gcode.resume_after)'
            if after > 0
            else f'plus the operator at {len(pauses)} pause(s) (~/resume)'
        )
        lines[0] += f', {waits}'
    lines.append('extents [mm]    lowest    highest   travel.min  travel.max  room below/above')
    for i, axis in enumerate('xyz'):
        tmin, tmax = travel.min[i], travel.max[i]
        lines.append(
            f'  {axis}        {1e3 * lo[i]:10.3f} {1e3 * hi[i]:10.3f} {1e3 * tmin:11.3f} '
            f'{1e3 * tmax:11.3f}  {1e3 * (lo[i] - tmin):.3f} / {1e3 * (tmax - hi[i]):.3f}'
        )
    for e in path.events:
        lines.append(f'{event_label(e)} at t = {e.time:.3f} s: {e.where}: {e.text}')
    return lines


def event_label(e: ProgramEvent) -> str:
    return {PAUSE: 'pause', TOOL_CHANGE: 'tool change'}.get(e.kind, e.channel or MESSAGE)


def _polyline(m: Move, tolerance: float) -> list[tuple[float, float, float]]:
    if m.kind == 'arc':
        return [m.start, *arc_points(m, tolerance)]
    return [m.start, m.end]


def draw(moves: Sequence[Move], path: GcodeTrajectory, output: Path, title: str) -> None:
    """XY, XZ and 3D views of the programmed path into a PNG."""
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(15, 5))
    xy = fig.add_subplot(1, 3, 1)
    xz = fig.add_subplot(1, 3, 2)
    d3 = fig.add_subplot(1, 3, 3, projection='3d')
    tolerance = path.tolerance
    for m in moves:
        if m.kind not in ('rapid', 'line', 'arc'):
            continue
        pts = _polyline(m, tolerance)
        xs, ys, zs = ([1e3 * p[i] for p in pts] for i in range(3))
        style: dict[str, Any] = (
            {'linestyle': '--', 'color': 'tab:gray', 'linewidth': 0.8}
            if m.kind == 'rapid'
            else {'linestyle': '-', 'color': 'tab:blue', 'linewidth': 1.0}
        )
        xy.plot(xs, ys, **style)
        xz.plot(xs, zs, **style)
        d3.plot(xs, ys, zs, **style)
    marks = {PAUSE: ('o', 'tab:red', 'pause'), TOOL_CHANGE: ('^', 'tab:orange', 'tool change')}
    labelled: set[str] = set()
    for e in path.events:
        if e.kind not in marks:
            continue
        marker, color, name = marks[e.kind]
        p = [1e3 * c for c in path.sample(e.time).position]
        label = None if name in labelled else name
        labelled.add(name)
        xy.plot(p[0], p[1], marker=marker, color=color, linestyle='', label=label)
        xz.plot(p[0], p[2], marker=marker, color=color, linestyle='')
        d3.plot([p[0]], [p[1]], [p[2]], marker=marker, color=color, linestyle='')
    for ax, (a, b) in ((xy, ('x', 'y')), (xz, ('x', 'z'))):
        ax.set_xlabel(f'{a} [mm]')
        ax.set_ylabel(f'{b} [mm]')
        ax.set_aspect('equal', adjustable='datalim')
        ax.grid(True, linewidth=0.3)
    xy.set_title('XY (rapids dashed)')
    xz.set_title('XZ')
    d3.set_title('3D')
    d3.set_xlabel('x [mm]')
    d3.set_ylabel('y [mm]')
    d3.set_zlabel('z [mm]')
    if labelled:
        xy.legend(loc='best', fontsize='small')
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(output, dpi=100)
    plt.close(fig)


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog='gcode-preview',
        description='Read, check and plan a G-code part program as the trajectory node does, '
        "print its machine time, its extents against the machine's travel and every pause, "
        'tool change and message, and draw its path (XY, XZ, 3D; rapids dashed) into a PNG. '
        'Nothing moves.',
        epilog='exit codes: 0 the program runs; 1 it is refused (one line: file:line:column: '
        'what); 2 usage',
    )
    p.add_argument('program', help='the G-code (RS274/NGC) file')
    p.add_argument(
        '--output', '-o', type=Path, help='the PNG to write (default: PROGRAM with .png)'
    )
    p.add_argument(
        '--param',
        '-p',
        action='append',
        default=[],
        metavar='NAME=VALUE',
        help='a trajectory parameter, e.g. gcode.start=[0,0,0.01] or travel.max=[0.2,0.2,0.1] '
        '(YAML value; repeatable)',
    )
    return p


def main(argv: list[str] | None = None) -> int:
    release_stop_signals()  # held since the first line (mill_common.executable)
    args = parser().parse_args(argv)
    if not Path(args.program).is_file():
        print(f'gcode-preview: {args.program}: no such G-code file', file=sys.stderr)
        return 1
    try:
        values = values_of(args.program, args.param)
        path = build_job(values).trajectory
        assert isinstance(path, GcodeTrajectory)
    except ParameterError as exc:  # the reader's one line, without the parameter's name
        reason = exc.reason if exc.name in ('file', 'tool_table') else str(exc)
        print(f'gcode-preview: {reason}', file=sys.stderr)
        return 1
    except (GcodeError, ValueError) as exc:
        print(f'gcode-preview: {exc}', file=sys.stderr)
        return 1
    for line in report(path, values):
        print(line)
    output = args.output or Path(args.program).with_suffix('.png')
    draw(path.moves, path, output, Path(args.program).name)
    print(f'path drawn in {output}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
