"""The feed report: per block the programmed F and the speed the plan achieves."""

from __future__ import annotations

import math

import pytest
from mill_trajectory.feed_report import block_feeds, feed_held, feed_summary, pieces_by_block
from mill_trajectory.gcode import parse_program
from mill_trajectory.planner import Limits, plan

LIMITS = Limits((0.05,) * 3, (0.5,) * 3, (10.0,) * 3, 1e-5)


def _report(text: str):
    moves = parse_program(text, 'part.ngc', (0.0, 0.0, 0.0))
    pieces, blocks = pieces_by_block(moves, LIMITS.tolerance)
    planned = plan(pieces, LIMITS)
    return block_feeds(moves, pieces, blocks, planned), planned


def test_a_long_line_reaches_its_feed_and_its_mean_is_its_length_over_its_time() -> None:
    # 100 mm at 10 mm/s from rest to rest: 10 s at F, plus the start and the stop.
    feeds, planned = _report('G21 G90 G1 X100 F600\nM30\n')
    (line,) = feeds
    assert line.kind == 'line' and line.feed == pytest.approx(0.01, rel=1e-12)
    assert line.peak == pytest.approx(0.01, rel=1e-12)
    assert line.length == pytest.approx(0.1, rel=1e-12)
    # The only move: the plan is its time and the halves of the start's and the stop's
    # transitions, spent at rest on the sharp timeline.
    start, stop = planned.transitions[1], planned.transitions[-1]
    assert line.time + 0.5 * (start + stop) == pytest.approx(planned.end_time, rel=1e-12)
    # Speeding up from rest and slowing down to it cost a little.
    assert 10.0 < line.time < 10.0 + 0.3
    assert line.mean == pytest.approx(0.1 / line.time, rel=1e-12)
    assert feed_held(feeds, 'line') == pytest.approx(10.0 / line.time, rel=1e-12)
    assert feed_held(feeds, 'arc') is None
    assert feed_summary(feeds) == f'feed held: {1000.0 / line.time:.0f} % of F on lines'


def test_blocks_keep_their_own_feed_and_the_summary_names_arcs_and_lines() -> None:
    text = 'G21 G90 G17\nG0 X40\nG1 X50 F300\nG3 X50 Y0 I-5 J0 F600\nG1 X70 F1200\nM30\n'
    feeds, planned = _report(text)
    assert [f.kind for f in feeds] == ['rapid', 'line', 'arc', 'line']
    rapid, slow, arc, fast = feeds
    assert rapid.feed is None and rapid.peak == pytest.approx(0.05, rel=1e-12)
    assert slow.peak == pytest.approx(0.005, rel=1e-12)
    assert fast.peak == pytest.approx(0.02, rel=1e-12)
    assert arc.length == pytest.approx(2 * math.pi * 0.005, rel=1e-3)  # chords: sag 5 µm
    assert arc.peak <= 0.01 and arc.mean <= arc.peak
    rests = 0.5 * (planned.transitions[1] + planned.transitions[-1])
    assert sum(f.time for f in feeds) + rests == pytest.approx(planned.end_time, rel=1e-12)
    held_arcs = feed_held(feeds, 'arc')
    assert held_arcs == pytest.approx(arc.length / 0.01 / arc.time, rel=1e-12)
    summary = feed_summary(feeds)
    assert summary.startswith(f'feed held: {100 * held_arcs:.0f} % of F on arcs, ')
    assert summary.endswith(' % on lines')


def test_a_surfacing_raster_holds_most_of_its_feed_on_lines() -> None:
    # 40 mm rows 0.5 mm apart at 20 mm/s: each 90 degree corner within 0.01 mm slows to
    # ~2.3 mm/s, the rows are cut next to it and ramp back up; the step overs run whole.
    rows = ['G21 G90 G17', 'G1 X0 Y0 F1200']
    for k in range(10):
        rows += [f'X{40 if k % 2 == 0 else 0}', f'Y{0.5 * (k + 1):g}']
    feeds, _ = _report('\n'.join(rows) + '\nM30\n')
    held = feed_held(feeds, 'line')
    assert held is not None and 0.84 <= held < 0.95  # 0.79 before transitions overlapped
    long_rows = [f for f in feeds if f.length > 0.039]
    assert all(f.peak == pytest.approx(0.02, rel=1e-12) for f in long_rows)
    # A row: 2 s at F, plus about 0.15 s for its two corners.
    assert all(2.0 < f.time < 2.2 for f in long_rows)
