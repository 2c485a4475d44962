"""How much of the programmed feed a planned G-code program holds, block by block. ROS-free.

For each block (one G-code move: a line, an arc, a rapid) of a planned program:

- programmed F [m/s] (None for a rapid: as fast as the axes allow);
- achieved peak speed [m/s]: the fastest planned speed of its pieces (mill_trajectory.
  planner), which the planned path reaches where a piece's transitions do not overlap; on
  a curve of short chords the blended speed runs a little below it;
- achieved mean speed [m/s]: its length over the time the plan spends on it (on the sharp
  timeline: each corner's transition is centred on the corner, so the plan's total time is
  the sum of these).

`feed_held` sums a kind of block (arcs, lines): the time its blocks would take at their
feed over the time they take as planned, so 100 % is every block at F from end to end and
1/3 a program that takes three times its feed time. A block whose own corners or short
pieces hold it below F counts in full: the figure is what an operator sees on the clock.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from mill_trajectory.gcode_words import Move
from mill_trajectory.planner import Piece, PlannedPath
from mill_trajectory.toolpath import pieces_of


@dataclass(frozen=True)
class BlockFeed:
    """One block's programmed feed and the speed its plan achieves."""

    move: Move
    feed: float | None  # programmed F [m/s]; None: a rapid
    length: float  # [m], along its pieces (chords for an arc)
    time: float  # planned [s]
    peak: float  # planned [m/s]
    mean: float  # length / time [m/s]

    @property
    def kind(self) -> str:
        return self.move.kind


def pieces_by_block(moves: Sequence[Move], tolerance: float) -> tuple[list[Piece], list[int]]:
    """The planner's pieces of `moves` (as toolpath.pieces_of) and the move each comes from."""
    pieces: list[Piece] = []
    blocks: list[int] = []
    for i, m in enumerate(moves):
        own, _ = pieces_of([m], tolerance)
        pieces += own
        blocks += [i] * len(own)
    return pieces, blocks


def block_feeds(
    moves: Sequence[Move], pieces: Sequence[Piece], blocks: Sequence[int], planned: PlannedPath
) -> list[BlockFeed]:
    """Per moving block (line, arc, rapid) of a planned program: F, peak and mean speed."""
    time, speed = planned.piece_times(len(pieces))
    n = len(moves)
    length = [0.0] * n
    spent = [0.0] * n
    peak = [0.0] * n
    for k, (piece, b) in enumerate(zip(pieces, blocks, strict=True)):
        if piece.rest:
            continue
        length[b] += math.dist(piece.start, piece.end)
        spent[b] += float(time[k])
        peak[b] = max(peak[b], float(speed[k]))
    out = []
    for b, m in enumerate(moves):
        if m.kind not in ('line', 'arc', 'rapid') or spent[b] <= 0.0:
            continue
        out.append(BlockFeed(m, m.feed, length[b], spent[b], peak[b], length[b] / spent[b]))
    return out


def feed_held(feeds: Sequence[BlockFeed], kind: str) -> float | None:
    """Feed time over planned time of the blocks of `kind` (None: no such block)."""
    at_feed = sum(f.length / f.feed for f in feeds if f.kind == kind and f.feed)
    planned = sum(f.time for f in feeds if f.kind == kind and f.feed)
    return at_feed / planned if planned > 0.0 else None


def feed_summary(feeds: Sequence[BlockFeed]) -> str:
    """'feed held: 97 % of F on arcs, 99 % on lines' (the kinds the program has)."""
    parts: list[str] = []
    for kind, name in (('arc', 'arcs'), ('line', 'lines')):
        held = feed_held(feeds, kind)
        if held is not None:
            parts.append(
                f'{100.0 * held:.0f} % of F on {name}'
                if not parts
                else f'{100.0 * held:.0f} % on {name}'
            )
    return 'feed held: ' + (', '.join(parts) if parts else 'no feed moves')
