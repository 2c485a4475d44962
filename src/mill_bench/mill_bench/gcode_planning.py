"""Benchmark: how fast G-code programs are read and planned, and how much feed they hold.

    python -m mill_bench.gcode_planning                 # a 40,000-line surfacing raster
    python -m mill_bench.gcode_planning --lines 4000    # a shorter one
    python -m mill_bench.gcode_planning --circles       # plus the feed held on circles
                                                        # (one turn, and the middle of three)

The raster (generated, not read from a file: the reading is timed from the text) faces a
40 mm wide part in rows 0.5 mm apart at 1200 mm/min (20 mm/s), as a CAM system writes it:
one G1 per row and one per step over. Printed: program lines per CPU second for reading
(mill_trajectory.gcode), cutting into pieces (toolpath) and planning (planner) apart and
together, and the feed held (mill_trajectory.feed_report). The machine is the gcode path's
default: 0.05 m/s, 0.5 m/s², 10 m/s³ per axis, 0.01 mm tolerance.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable
from typing import TypeVar

from mill_trajectory.feed_report import block_feeds, feed_summary, pieces_by_block
from mill_trajectory.gcode import parse_program
from mill_trajectory.gcode_program import (
    DEFAULT_ACCELERATION,
    DEFAULT_JERK,
    DEFAULT_TOLERANCE,
    DEFAULT_VELOCITY,
)
from mill_trajectory.planner import Limits, plan, xyz
from mill_trajectory.toolpath import pieces_of

T = TypeVar('T')
LIMITS = Limits(
    xyz(DEFAULT_VELOCITY), xyz(DEFAULT_ACCELERATION), xyz(DEFAULT_JERK), DEFAULT_TOLERANCE
)


def surfacing(lines: int, width: float = 40.0, step: float = 0.5, feed: float = 1200.0) -> str:
    """A zig-zag raster of `lines` program lines [mm, mm/min]."""
    out = ['G21 G90 G17', f'G1 X0 Y0 F{feed:g}']
    row = 0
    while len(out) < lines - 1:
        x = width if row % 2 == 0 else 0.0
        out.append(f'X{x:g}')
        out.append(f'Y{(row + 1) * step:g}')
        row += 1
    out.append('M30')
    return '\n'.join(out[:lines]) + '\n'


def circle(radius: float, feed: float, turns: int = 1) -> str:
    """`turns` full circles of `radius` [mm] at `feed` [mm/s], after a rapid to the start
    (a 90 degree corner with it) and to rest at the end."""
    arc = f'G3 X{radius:g} Y0 I{-radius:g} J0 F{60 * feed:g}\n'
    return f'G21 G90 G17\nG0 X{radius:g} Y0\n{arc * turns}M30\n'


def _cpu(fn: Callable[..., T], *args: object) -> tuple[T, float]:
    t = time.process_time()
    out = fn(*args)
    return out, time.process_time() - t


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--lines', type=int, default=40000, help='program lines (default 40000)')
    ap.add_argument('--circles', action='store_true', help='also the feed held on circles')
    args = ap.parse_args(argv)
    text = surfacing(args.lines)
    count = text.count('\n')
    moves, t_read = _cpu(parse_program, text, 'surfacing.ngc', (0.0, 0.0, 0.0))
    (pieces, _), t_cut = _cpu(pieces_of, moves, LIMITS.tolerance)
    planned, t_plan = _cpu(plan, pieces, LIMITS)
    total = t_read + t_cut + t_plan
    print(f'surfacing raster: {count} lines, {len(pieces)} pieces, {planned.end_time:.1f} s')
    for name, t in (('read', t_read), ('pieces', t_cut), ('plan', t_plan), ('total', total)):
        print(f'  {name:7s} {t:8.3f} s CPU  {count / t:10.0f} lines/s')
    by_block, blocks = pieces_by_block(moves, LIMITS.tolerance)
    print('  ' + feed_summary(block_feeds(moves, by_block, blocks, plan(by_block, LIMITS))))
    if not args.circles:
        return
    a, j, v = LIMITS.acceleration[0], LIMITS.jerk[0], LIMITS.velocity[0]
    print(
        'circles (mm/s; allowed = min(F, v, sqrt(a r), (j r^2)^(1/3))): one turn from the '
        "rapid's corner to rest, and the middle one of three turns"
    )
    for radius in (0.25, 1.0, 5.0, 50.0):
        for feed in (10.0, 50.0):
            arcs = []
            for turns in (1, 3):
                text = circle(radius, feed, turns)
                moves = parse_program(text, 'circle.ngc', (0.0, 0.0, 0.0))
                pieces, blocks = pieces_by_block(moves, LIMITS.tolerance)
                feeds = block_feeds(moves, pieces, blocks, plan(pieces, LIMITS))
                arcs.append([f for f in feeds if f.kind == 'arc'][turns // 2])
            r = radius * 1e-3
            allowed = min(feed * 1e-3, v, math.sqrt(a * r), (j * r * r) ** (1 / 3))
            one, middle = arcs
            print(
                f'  r {radius:5g} mm F {feed:2g}: allowed {allowed * 1e3:5.1f}; one turn: '
                f'peak {one.peak * 1e3:5.1f}, mean {one.mean * 1e3:5.1f} '
                f'({100 * one.mean / allowed:3.0f} %); middle of three: mean '
                f'{middle.mean * 1e3:5.1f} ({100 * middle.mean / allowed:3.0f} %)'
            )


if __name__ == '__main__':
    main()
