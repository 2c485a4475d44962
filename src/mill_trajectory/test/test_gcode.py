"""The G-code reader: the subset's words, and one-line errors naming file:line:column."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from mill_trajectory.gcode import Setup, Tool, parse_program, read_program
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


@pytest.mark.parametrize(
    ('text', 'where', 'what'),
    [
        ('o1 while [1]\nG0 X1\no1 endwhile', 'part.ngc:3:1', 'runaway loop'),
        ('o1 do\no1 while [1]', 'part.ngc:2:1', 'runaway loop'),
        ('G0 X#<depth>', 'part.ngc:1:5', 'parameter #<depth> is used before it is set'),
        ('#1 = 0\nG0 X[2 / #1]', 'part.ngc:2:8', 'division by zero'),
        ('G0 X[5 MOD 0]', 'part.ngc:1:8', 'division by zero'),
        ('G0 X0\no7 if [1]\nG0 X1', 'part.ngc:2:1', 'o7 if is not closed (no o7 endif)'),
        ('o<pocket> sub\nG0 X1', 'part.ngc:1:1', 'o<pocket> sub is not closed'),
        ('o<pocket> call [1]', 'part.ngc:1:1', 'o<pocket> call: no such subroutine'),
        ('o2 call\no2 sub\no2 endsub', 'part.ngc:1:1', 'no such subroutine defined before it'),
        ('o1 while [1]\no2 endwhile', 'part.ngc:2:1', 'o2 endwhile without an open o2 while'),
        ('o1 sub\no2 sub\no2 endsub\no1 endsub', 'part.ngc:2:1', 'inside a sub'),
        ('o3 break', 'part.ngc:1:1', 'o3 break outside its o3 loop'),
        ('o1 if [1] G0 X1', 'part.ngc:1:11', 'takes nothing else on its line'),
        ('o1 if\no1 endif', 'part.ngc:1:6', 'needs a condition'),
        ('G0 X[1 + 2', 'part.ngc:1:5', '"[" is not closed'),
        ('G0 X[FOO[1]]', 'part.ngc:1:6', "unknown function 'FOO'"),
        ('G0 X[SQRT[-4]]', 'part.ngc:1:10', 'SQRT[-4] of a negative number'),
        ('#1', 'part.ngc:1:1', 'a parameter alone'),
        ('G93 G1 X1 F1', 'part.ngc:1:1', 'G93 inverse-time feed is not supported'),
        ('G95 G1 X1 F1', 'part.ngc:1:1', 'G95 feed per revolution is not supported'),
        ('G41.1 D4 G1 X1 F9', 'part.ngc:1:10', 'must be longer than the tool radius'),
        ('G0 X-9\nG41.1 D4 G2 X1 I5 F9', 'part.ngc:2:10', 'entry move must be G0 or G1'),
        ('G41.1 D4 G1 X9 F9\nG3 X10 Y1 I0 J1', 'part.ngc:2:1', 'not larger than the tool radius'),
        ('G41.1 D2\nG42.1 D2', 'part.ngc:2:1', 'cutter compensation is already on'),
        ('G41.1 D2\nG18', 'part.ngc:2:1', 'a plane change with cutter compensation on'),
        ('G41.1 D2\nG28', 'part.ngc:2:1', 'G28 with cutter compensation on'),
        ('G18 G41.1 D2', 'part.ngc:1:5', 'only in the G17 plane'),
        (
            'G41.1 D4 G1 X10 F9\nY0.5\nX0',
            'part.ngc:2:1',
            'too short for the tool radius (it would gouge)',
        ),
        ('G2 X10 Y0 I5 K1 F100', 'part.ngc:1:14', 'word K1 is not in the G17 plane'),
        ('G90.1 G2 X10 Y0 I5 F100', 'part.ngc:1:7', 'J missing'),
        ('G10 L1 P1 Z5', 'part.ngc:1:5', 'only G10 L2 and G10 L20'),
        ('G10 L2 P12 X1', 'part.ngc:1:8', 'must be 0..9'),
        ('G81 X1 Z-1 F10', 'part.ngc:1:1', 'G81 needs R'),
        ('G81 X1 Z1 R0 F10', 'part.ngc:1:1', 'R is below the hole bottom Z'),
        ('G83 X1 Z-1 R1 Q0 F10', 'part.ngc:1:15', 'peck depth Q must be > 0'),
        ('G81 X1 Z-1 R1 F10\nG82 X2', 'part.ngc:2:1', 'G82 needs R'),
        ('G18 G81 X1 Z-1 R1 F10', 'part.ngc:1:5', 'only in the G17'),
        ('G80 X1', 'part.ngc:1:1', 'axis words with G80'),
        ('G2 X1 Y1 I1 F10\nG53 X0', 'part.ngc:2:1', 'G53 needs G0 or G1'),
        ('G0 X1 Q2', 'part.ngc:1:7', 'word Q2 is not used on this line'),
        ('G1 X1 F10 L2', 'part.ngc:1:11', 'word L2 is not used on this line'),
        ('G92', 'part.ngc:1:1', 'G92 needs at least one of X, Y, Z'),
        ('G2 X1 Y0 I0.5 P0 F10', 'part.ngc:1:15', 'arc turns P0 must be a whole number >= 1'),
        ('G43.1', 'part.ngc:1:1', 'G43.1 needs an offset'),
        ('M6', 'part.ngc:1:1', 'M6 needs a tool: give T first'),
        ('T1.5', 'part.ngc:1:1', 'tool number T1.5 must be a whole number'),
        ('G0 X1 B2', 'part.ngc:1:7', "unsupported word 'B2'"),
    ],
)
def test_bad_programs_are_one_line_each(
    text: str, where: str, what: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    # A runaway loop is the same refusal after 1,000 passes as after 100,000, in 1 % of the time.
    monkeypatch.setattr('mill_trajectory.gcode_flow.ITERATIONS', 1000)
    with pytest.raises(GcodeError) as err:
        moves(text)
    message = str(err.value)
    assert '\n' not in message
    assert message.startswith(where + ': '), message
    assert what in message, message


def test_a_tool_not_in_the_table() -> None:
    setup = Setup(tools={1: Tool(1, (0.0, 0.0, 0.02))}, tool_table='tool.tbl')
    with pytest.raises(GcodeError, match=r'^part\.ngc:2:5: tool T2 is not in tool\.tbl$'):
        parse_program('T1 M6\nG43 H2', 'part.ngc', HOME, setup=setup)
    (m,) = parse_program('T1 M6 G43 H1\nG0 Z0', 'part.ngc', HOME, setup=setup)[1:]
    assert m.end == pytest.approx((0.0, 0.0, 0.02))


@pytest.mark.parametrize(
    ('expression', 'value'),
    [
        ('[1 + 2 * 3 ** 2]', 19.0),
        ('[2 ** 3 ** 2]', 64.0),  # left to right, as LinuxCNC
        ('[10 - 4 - 3]', 3.0),
        ('[7 MOD 3 + -7 MOD 3]', 3.0),  # a MOD b takes the sign of b
        ('[1 + 1 EQ 2]', 1.0),
        ('[0.1 + 0.2 EQ 0.3]', 1.0),
        ('[2 GT 1 AND 3 LE 2]', 0.0),
        ('[1 XOR 1 OR 0]', 0.0),
        ('[1 NE 2 AND 2 GE 2 AND 1 LT 2]', 1.0),
        ('[ATAN[1]/[-1]]', 135.0),
        ('[SIN[30] + COS[60] + TAN[45]]', 2.0),
        ('[ASIN[1] + ACOS[0]]', 180.0),
        ('[FIX[-1.5] + FUP[1.2] + ROUND[2.5] + ABS[-4]]', 7.0),
        ('[EXP[0] + LN[1] + SQRT[9]]', 4.0),
        ('-[2]', -2.0),
        ('#[1 + 1]', 5.0),
        ('##1', 5.0),
    ],
)
def test_expressions_read_as_linuxcnc(expression: str, value: float) -> None:
    ms = moves(f'#1 = 2\n#2 = 5\nG0 X{expression}', offset=(0.0, 0.0, 0.0))
    assert ms[-1].end[0] * 1000 == pytest.approx(value, abs=1e-9)


def test_a_parameter_set_on_a_line_is_new_from_the_next_line_on() -> None:
    ms = moves('#1 = 1\n#1 = 2 G0 X#1\nG0 X#1\n#<_a> = 3\n#<a> = 4\nG0 X[#<_a> * 10 + #<a>]')
    assert [round(m.end[0] * 1000, 9) for m in ms] == [1.0, 2.0, 34.0]


def test_subroutine_parameters_are_local_and_return_values() -> None:
    ms = moves(
        '#1 = 9\n#40 = 0\no<f> sub\n#40 = [#1 + #2]\n#1 = 100\no<f> endsub [#1 * 2]\n'
        'o<f> call [1] [2]\nG0 X#40 Y#1 Z#<_value>'
    )
    assert ms[-1].end == pytest.approx((0.003, 0.009, 0.2))


def test_program_numbers_percent_bom_block_delete_and_messages() -> None:
    text = '\ufeff%\nO1001 (PART)\n(MSG, check the vise)\n/G0 X1\nG0 Y1\n%\nG0 Z1\n'
    ms = moves(text)
    assert [(m.kind, m.message) for m in ms] == [
        ('message', 'check the vise'),
        ('rapid', ''),
        ('rapid', ''),
    ]
    assert ms[-1].end == pytest.approx((0.001, 0.001, 0.0))
    skipped = parse_program(text, 'part.ngc', HOME, setup=Setup(block_delete=True))
    assert skipped[-1].end == pytest.approx((0.0, 0.001, 0.0))


def test_arc_end_tolerance_is_linuxcnc_s() -> None:
    # 0.02 mm off on a 5 mm radius: within 0.028 mm (though 0.4 %): accepted.
    (ok,) = moves('G2 X10.02 Y0 I5 F100')
    assert ok.end == pytest.approx((0.01002, 0.0, 0.0))
    # 0.5 % of a 1 m radius (5 mm): more than 0.1 % and more than 0.028 mm: refused.
    with pytest.raises(GcodeError, match='not on its circle'):
        moves('G2 X2005 Y0 I1000 F100')
    # 0.1 % of a 4 m radius is 4 mm, but at most 100 x 0.028 mm = 2.83 mm is accepted.
    with pytest.raises(GcodeError, match='not on its circle'):
        moves('G2 X8003 Y0 I4000 F100')
    (big,) = moves('G2 X8002 Y0 I4000 F100')
    assert big.sweep == pytest.approx(-math.pi, abs=1e-3)


def test_f_on_a_units_line_is_read_before_the_units_change() -> None:
    (m,) = moves('G20 F10 G1 X1')  # LinuxCNC: F, then G20: 10 mm/min
    assert m.feed == pytest.approx(0.01 / 60) and m.end[0] == pytest.approx(0.0254)
    (m,) = moves('G20\nF10 G1 X1')
    assert m.feed == pytest.approx(0.254 / 60)
