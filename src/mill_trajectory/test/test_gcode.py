"""The G-code reader: the subset's words, and one-line errors naming file:line:column."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from mill_trajectory.gcode import parse_program, read_program
from mill_trajectory.gcode_words import GcodeError

HOME = (0.0, 0.0, 0.0)


def moves(text: str, start=HOME, offset=(0.0, 0.0, 0.0)):
    return parse_program(text, 'part.ngc', start, offset)


def test_lines_units_modes_and_feed() -> None:
    ms = moves('N1 G21 G90 F600 (mm/min)\nG1 X10 Y-5 ; cut\nG91 G1 Z-2\nG20 G90 G0 X1\n')
    assert [m.kind for m in ms] == ['line', 'line', 'rapid']
    assert ms[0].end == (0.01, -0.005, 0.0)
    assert ms[0].feed == pytest.approx(0.01)  # 600 mm/min
    assert ms[1].end == pytest.approx((0.01, -0.005, -0.002))
    assert ms[2].end == pytest.approx((0.0254, -0.005, -0.002))
    assert ms[2].feed is None


def test_mm_coordinates_are_the_yaml_floats() -> None:
    (m,) = moves('G1 X-75 Y-105.0 Z-5 F180', start=(-0.075, 0.0, 0.0))
    assert m.end == (-0.075, -0.105, -0.005)
    assert m.feed == 0.003


def test_g92_and_work_offset() -> None:
    ms = moves('G92 X0 Y0\nG1 X1 F60\n', start=(0.01, 0.02, 0.0), offset=(0.5, 0.5, 0.5))
    assert ms[0].end == pytest.approx((0.011, 0.02, 0.0))
    (m,) = moves('G1 Z1 F60', offset=(0.0, 0.0, -0.01))
    assert m.end == pytest.approx((0.0, 0.0, -0.009))


def test_arcs_ijk_and_r_agree() -> None:
    # Quarter circle, radius 10 mm, counter-clockwise from (10, 0) to (0, 10) about 0.
    (ijk,) = moves('G3 X0 Y10 I-10 J0 F100', start=(0.01, 0.0, 0.0))
    (r,) = moves('G3 X0 Y10 R10 F100', start=(0.01, 0.0, 0.0))
    assert ijk.center == pytest.approx((0.0, 0.0, 0.0), abs=1e-15)
    assert r.center == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    assert ijk.sweep == pytest.approx(math.pi / 2) and r.sweep == pytest.approx(math.pi / 2)
    (cw,) = moves('G2 X0 Y10 R-10 F100', start=(0.01, 0.0, 0.0))  # the long way round
    assert cw.sweep == pytest.approx(-1.5 * math.pi)
    (full,) = moves('G2 I5 J0 X0 F100')
    assert full.sweep == pytest.approx(-2 * math.pi)


def test_planes_dwell_spindle_and_end() -> None:
    ms = moves('M3 S1000\nG18 G2 X10 Z0 I5 K0 F100\nG4 P0.5\nM5\nM0\nM30\nG1 X99\n')
    assert [m.kind for m in ms] == ['spindle', 'arc', 'dwell', 'spindle', 'stop']
    assert ms[0].spindle == 1000.0 and ms[1].spindle == 1000.0
    assert ms[1].plane == (2, 0, 1)
    assert ms[2].duration == 0.5
    assert ms[3].spindle == 0.0 and ms[4].spindle == 0.0  # M5 before M0


def test_spindle_speed_direction_and_changes() -> None:
    ms = moves('S500 M4\nG1 X1 F100\nS800\nG1 X2\nM3\nM3\nM5 S0\n')
    assert [(m.kind, m.spindle) for m in ms] == [
        ('spindle', -500.0),
        ('line', -500.0),
        ('spindle', -800.0),  # a new speed while it runs: a change, at rest
        ('line', -800.0),
        ('spindle', 800.0),  # M3 again: no change, no move
        ('spindle', 0.0),
    ]


@pytest.mark.parametrize(
    ('text', 'where', 'what'),
    [
        ('G1 X1 F100\nG1 X2 A1', 'part.ngc:2:7', "unsupported word 'A1'"),
        ('G0 X1\nG33 Z1', 'part.ngc:2:1', 'unsupported code G33'),
        ('M6', 'part.ngc:1:1', 'M6 needs a tool: give T first'),
        ('G1 X1 F100\nM3', 'part.ngc:2:1', 'M3 needs a spindle speed: give S first'),
        ('G1 X1.2.3 F100', 'part.ngc:1:5', "malformed number '1.2.3'"),
        ('G1 X F100', 'part.ngc:1:4', 'word X has no number'),
        ('G1 X1 F0', 'part.ngc:1:7', 'feed F0 must be > 0'),
        ('G1 X1', 'part.ngc:1:1', 'no feed'),
        ('G2 X30 Y0 R10 F100', 'part.ngc:1:11', 'does not reach its end point'),
        ('G2 X10 Y1 I5 F100', 'part.ngc:1:1', 'not on its circle'),
        ('G1 X1 F100 (open', 'part.ngc:1:12', 'not closed'),
        ('G4', 'part.ngc:1:1', 'G4 needs P'),
        ('G0 G1 X1', 'part.ngc:1:4', 'G1 and G0 on one line'),
        ('\n\nX1', 'part.ngc:3:1', 'without a motion'),
        ('G1 X1 X2 F9', 'part.ngc:1:7', 'appears twice'),
    ],
)
def test_bad_input_is_one_line_naming_file_line_column(text: str, where: str, what: str) -> None:
    with pytest.raises(GcodeError) as err:
        moves(text)
    message = str(err.value)
    assert '\n' not in message
    assert message.startswith(where + ': '), message
    assert what in message, message


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(GcodeError, match=r'nope\.ngc.*no such G-code file'):
        read_program(tmp_path / 'nope.ngc', HOME)
