"""gcode-preview on the corpus: its figures are the planner's, its PNG is written, and a bad
program is refused in the reader's one line."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from mill_trajectory.config import build_job
from mill_trajectory.preview import main, sample_step, values_of

PROGRAMS = Path(__file__).resolve().parent / 'programs'


def test_the_preview_prints_the_planners_time_extents_and_pauses(tmp_path, capsys) -> None:
    program = str(PROGRAMS / 'modal_words.ngc')
    png = tmp_path / 'part.png'
    assert main([program, '--output', str(png), '-p', 'travel.max=[0.2, 0.2, 0.2]']) == 0
    out = capsys.readouterr().out.splitlines()
    path = build_job(values_of(program, ['travel.max=[0.2, 0.2, 0.2]'])).trajectory
    time = re.match(r'machine time ([\d.]+) s \(planned; feed held: ', out[0])
    assert time is not None and float(time.group(1)) == round(path.end_time, 3)
    assert out[0].endswith('plus the operator at 2 pause(s) (~/resume)')
    lo, hi = path.bounds(sample_step(path))
    for i, axis in enumerate('xyz'):
        row = next(line.split() for line in out if line.startswith(f'  {axis} '))
        figures = [float(v) for v in row[1:5]]
        assert figures == pytest.approx([1e3 * lo[i], 1e3 * hi[i], -1000.0, 200.0], abs=5e-4), axis
    # N140 M1 (the optional stop on, by default) and N150 M0, where the path is at rest.
    pauses = [line for line in out if line.startswith('pause at t = ')]
    assert [p.split(': ', 2)[1].rsplit(':', 2)[1] for p in pauses] == ['16', '17']
    assert pauses[0].endswith('M1: optional stop') and pauses[1].endswith('M0: program stop')
    assert png.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n' and png.stat().st_size > 20_000


def test_a_bad_program_is_refused_in_the_readers_one_line(tmp_path, capsys) -> None:
    part = tmp_path / 'bad.ngc'
    part.write_text('G1 X10 F100\nG1 Y10 Q3\n')
    png = tmp_path / 'bad.png'
    assert main([str(part), '--output', str(png)]) == 1
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and err.startswith(f'gcode-preview: {part}:2:8: word Q3')
    assert not png.exists()
    assert main([str(PROGRAMS / 'modal_words.ngc'), '-p', 'travel.max=[0.001, 1, 1]']) == 1
    err = capsys.readouterr().err
    assert re.fullmatch(
        r'gcode-preview: \S+modal_words\.ngc:\d+:\d+: move outside the machine travel: x = .*\n',
        err,
    )
