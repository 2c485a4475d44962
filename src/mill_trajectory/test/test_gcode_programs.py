"""Whole programs in the style of real CAM posts and hand-written LinuxCNC programs
(test/programs/): each parses and plans with the default limits, and its path goes
through hand-computed points (tool lengths, work offsets, canned cycles, sub calls)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from mill_common.parameters import ParameterError
from mill_trajectory.gcode import Setup, read_program, read_tool_table
from mill_trajectory.gcode_program import GcodeTrajectory
from mill_trajectory.gcode_words import Move

PROGRAMS = Path(__file__).resolve().parent / 'programs'
TOOLS = PROGRAMS / 'tools.tbl'
NAMES = sorted(p.name for p in PROGRAMS.iterdir() if p.suffix in ('.ngc', '.nc'))
HOME = (0.0, 0.0, 0.0)


def _setup(**given) -> Setup:
    return Setup(tools=read_tool_table(TOOLS), tool_table=str(TOOLS), **given)


def _moves(name: str, **given) -> list[Move]:
    return read_program(PROGRAMS / name, HOME, setup=_setup(**given))


def _at(moves: list[Move], line: int, kind: str | None = None) -> list[Move]:
    return [m for m in moves if m.where.line == line and kind in (None, m.kind)]


def _mm(moves: list[Move]) -> list[tuple[float, ...]]:
    """The end points of moves [mm], rounded off to 1e-6 mm."""
    return [tuple(round(v * 1e3, 6) + 0.0 for v in m.end) for m in moves]


def test_there_are_a_dozen_programs() -> None:
    assert len(NAMES) >= 12


@pytest.mark.parametrize('name', NAMES)
def test_each_program_parses_and_plans_with_the_default_limits(name: str) -> None:
    values = {spec.name: spec.default for spec in GcodeTrajectory.PARAMETERS}
    values |= {'file': str(PROGRAMS / name), 'tool_table': str(TOOLS)}
    path = GcodeTrajectory.from_parameters(values)
    moves = read_program(PROGRAMS / name, HOME, setup=_setup())
    assert path.end_time > 0.0
    assert path.planned.end_point == pytest.approx(moves[-1].end, abs=1e-12)
    assert path.sample(path.end_time + 1.0).position == pytest.approx(moves[-1].end, abs=1e-12)


def test_fusion_linuxcnc_tool_length_contour_and_drilling() -> None:
    ms = _moves('fusion_linuxcnc.ngc')
    (change,) = _at(ms, 9)
    assert change.kind == 'stop' and 'T1' in change.message and '6 mm' in change.message
    assert _mm(_at(ms, 6)) == [(0.0, 0.0, 0.0)]  # G53 G0 Z0.
    assert _mm(_at(ms, 14)) == [(-5.0, 0.0, 40.0)]  # G43 Z15. H1: T1 is 25 mm long
    (cut,) = _at(ms, 16)
    assert _mm([cut]) == [(-5.0, 0.0, 22.0)] and cut.feed == pytest.approx(0.005)
    assert cut.coolant == 'flood' and cut.spindle == 8000.0
    (arc,) = _at(ms, 18)  # G3 X30. Y10. I0. J10. K0.
    assert arc.center == pytest.approx((0.02, 0.01, 0.022))
    assert arc.sweep == pytest.approx(math.pi / 2)
    # G98 G81 X10. Y10. Z-4. R3. from Z15. (machine 40): R at 28, the bottom at 21.
    assert _mm(_at(ms, 27)) == [(10, 10, 40), (10, 10, 28), (10, 10, 21), (10, 10, 40)]
    assert _mm(_at(ms, 28)) == [(20, 20, 40), (20, 20, 28), (20, 20, 21), (20, 20, 40)]
    assert [m.kind for m in _at(ms, 27)] == ['rapid', 'rapid', 'line', 'rapid']
    assert _at(ms, 27, 'line')[0].feed == pytest.approx(0.0025)  # F150.
    assert _mm(_at(ms, 32)) == [(20, 20, 40), (20, 20, 0)]  # G91 G28 Z0.
    assert ms[-1].coolant == '' and ms[-1].spindle == 0.0


def test_haas_peck_drilling_machine_moves_and_two_tools() -> None:
    ms = _moves('haas_pocket.nc')
    assert _mm(_at(ms, 8)) == [(15, 15, 60)]  # G43 H02 Z20.: T2 is 40 mm long
    # G83 G98 Z-6. R2. Q2.5: R at 42, bottom at 34, pecks of 2.5 mm, 1 mm above the last.
    zs = [p[2] for p in _mm(_at(ms, 9))]
    assert zs == [60, 42, 39.5, 42, 40.5, 37, 42, 38, 34.5, 42, 35.5, 34, 60]
    assert [m.kind for m in _at(ms, 9)][2:5] == ['line', 'rapid', 'rapid']
    assert _mm(_at(ms, 10))[-1] == (35, 15, 60)
    assert _mm(_at(ms, 13)) == [(35, 15, 0)]  # G53 G49 Z0. after G80: a rapid
    assert _mm(_at(ms, 17)) == [(25, 25, 35)]  # T1, 25 mm
    (circle,) = _at(ms, 19)
    assert circle.sweep == pytest.approx(-2 * math.pi)
    assert circle.center == pytest.approx((0.02, 0.025, 0.024))
    (half,) = _at(ms, 20)  # G03 X30. Y25. R2.5 from X25.: a half circle
    assert half.sweep == pytest.approx(math.pi) and half.center[:2] == pytest.approx(
        (0.0275, 0.025)
    )


def test_freecad_profile_with_k0_words() -> None:
    ms = _moves('freecad_linuxcnc.ngc')
    assert _mm(_at(ms, 16)) == [(0, 0, 33)]
    arcs = _at(ms, 20) + _at(ms, 21)
    assert [a.sweep for a in arcs] == pytest.approx([math.pi / 2, math.pi / 2])
    assert _mm(arcs) == [(0, 10, 23), (-10, 0, 23)]


def test_grbl_feed_alone_and_full_circles() -> None:
    ms = _moves('grbl_circles.nc')
    (plunge,) = _at(ms, 9)
    assert plunge.feed == pytest.approx(0.005)  # 'G1 F300' set it
    (cw,) = _at(ms, 10)
    (ccw,) = _at(ms, 11)
    assert cw.start == cw.end == ccw.end
    assert cw.sweep == pytest.approx(-2 * math.pi) and ccw.sweep == pytest.approx(2 * math.pi)
    assert cw.center == pytest.approx((0.01, 0.01, -0.001))
    (half,) = _at(ms, 13)
    assert half.sweep == pytest.approx(-math.pi) and _mm([half]) == [(0, 10, -2)]


def test_hand_written_inch_program_with_named_parameters_and_g55() -> None:
    ms = _moves('linuxcnc_inch.ngc')
    (msg,) = _at(ms, 6)
    assert msg.kind == 'message' and msg.message == 'cutting the slot in G55'
    assert _mm(_at(ms, 7)) == [(25.4, 12.7, 2.54)]
    (down,) = _at(ms, 8)
    assert _mm([down]) == [(25.4, 12.7, -1.27)]
    assert down.feed == pytest.approx(20 * 0.0254 / 60)
    assert down.tolerance == pytest.approx(0.0005 * 0.0254)
    assert _mm(_at(ms, 9)) == [(76.2, 12.7, -1.27)]
    assert _mm(_at(ms, 11)) == [(0, 0, 2.54)]
    assert _mm(_at(ms, 12)) == [(127, 0, 2.54)]  # block delete switch off
    skipped = _moves('linuxcnc_inch.ngc', block_delete=True)
    assert _at(skipped, 12) == []


def test_parametric_bolt_circle_and_spiral() -> None:
    ms = _moves('parametric_bolt_circle.ngc')
    holes = _at(ms, 9)
    assert _mm(holes) == [(20, 0, 2), (0, 20, 2), (-20, 0, 2), (0, -20, 2)]
    assert [p[2] for p in _mm(_at(ms, 10))] == [-3, -3, -3, -3]
    spiral = _mm(_at(ms, 26) + _at(ms, 27))
    assert sorted(spiral) == sorted(
        [(2, 0, -1), (2, 2, -1), (6, 2, -1), (6, 6, -1), (12, 6, -1), (12, 12, -1)]
    )


def test_every_canned_cycle() -> None:
    ms = _moves('drill_cycles.ngc')
    # G99 G81: from Z10 down to R2, feed to -5, back to R (G99).
    assert _mm(_at(ms, 4)) == [(10, 0, 10), (10, 0, 2), (10, 0, -5), (10, 0, 2)]
    g82 = _at(ms, 5)
    assert _mm(g82) == [(20, 0, 2), (20, 0, -5), (20, 0, -5), (20, 0, 2)]
    assert g82[2].kind == 'dwell' and g82[2].duration == 0.5
    # G98 G73 Q1.5: chip breaking, 1 mm back up; then back to the initial Z10.
    zs = [p[2] for p in _mm(_at(ms, 6))]
    assert zs == [2, 1, -0.5, 0.5, -2, -1, -3.5, -2.5, -4, 10]
    # G83 D0.5: out to R after each peck, then down to 0.5 mm above it.
    zs = [p[2] for p in _mm(_at(ms, 7))]
    assert zs == [10, 1, -0.5, 1, 0, -2, 1, -1.5, -3.5, 1, -3, -4, 10]
    g85 = _at(ms, 8)
    assert [m.kind for m in g85] == ['rapid', 'rapid', 'line', 'line', 'rapid']
    assert [p[2] for p in _mm(g85)] == [10, 2, -3, 2, 10]
    g89 = _at(ms, 9)
    assert [m.kind for m in g89] == ['rapid', 'rapid', 'line', 'dwell', 'line']
    assert [p[2] for p in _mm(g89)] == [10, 2, -3, -3, 10]
    # G91 G99 G81 X10 Y0 Z-4 R-3 L3 from (0, 10, 5): R at 2, bottom at -2, three holes.
    bottoms = [p for p, m in zip(_mm(_at(ms, 12)), _at(ms, 12), strict=True) if m.kind == 'line']
    assert bottoms == [(10, 10, -2), (20, 10, -2), (30, 10, -2)]
    assert _mm(_at(ms, 12))[-1] == (30, 10, 2)
    assert all(m.exact_stop for m in _at(ms, 4) + _at(ms, 12))
    assert not _at(ms, 14)[0].exact_stop


def test_work_offsets_g92_g52_g53_and_home_positions() -> None:
    ms = _moves('offsets.ngc', home=(0.05, 0.06, 0.07), home2=(-0.01, -0.02, 0.03))
    assert _mm(_at(ms, 5)) == [(10, 20, 5)]  # G54 set by G10 L2 P1
    assert _mm(_at(ms, 6)) == [(-30, 5, 3)]  # G56 set by G10 L2 P3
    assert _mm(_at(ms, 7)) == [(1, 1, 3)]  # G59.3: zero offsets
    assert _mm(_at(ms, 9)) == [(1, 1, 3)]  # G10 L20 P9 X0 Y0: here is its zero
    assert _mm(_at(ms, 12)) == [(6, 6, 3)]  # G92 X0 Y0 at (1, 1) in G54
    assert _mm(_at(ms, 14)) == [(15, 25, 3)]  # G92.1
    assert _mm(_at(ms, 16)) == [(110, 25, 3)]  # G52 X100
    assert _mm(_at(ms, 18)) == [(110, 25, 0)]  # G53 G0 Z0
    assert _mm(_at(ms, 19)) == [(10, 20, 0)]
    assert _mm(_at(ms, 20)) == [(-10, -20, 30)]  # G30
    assert _mm(_at(ms, 21)) == [(-10, -20, 30), (-10, -20, 70)]  # G28 G91 Z0: z only
    assert _mm(_at(ms, 23)) == [(50, 60, 70)]  # G28


def test_tool_length_offsets() -> None:
    ms = _moves('tool_lengths.ngc')
    assert [p[2] for p in _mm(_at(ms, 5))] == [35]  # G43 H1: 25 mm
    assert [p[2] for p in _mm(_at(ms, 7))] == [10]  # G49
    assert [p[2] for p in _mm(_at(ms, 10))] == [22.5]  # G43 with T5 loaded: 12.5 mm
    assert [p[2] for p in _mm(_at(ms, 12))] == [9]  # G43.1 Z-1
    assert _mm(_at(ms, 15)) == [(5, 0, 40)]  # G43 H2: 40 mm
    assert [m.message for m in ms if m.kind == 'stop'] == [
        'tool change: put in T1, 6 mm diameter, 6 mm flat end mill',
        'tool change: put in T5, 10 mm diameter, 10 mm face mill',
    ]


def test_arcs_in_every_plane_absolute_centres_and_turns() -> None:
    ms = _moves('arcs_planes.ngc')
    (a,) = _at(ms, 4)
    (b,) = _at(ms, 6)  # G90.1: I0 J0 is the centre itself
    assert a.sweep == pytest.approx(math.pi / 2) and b.sweep == pytest.approx(math.pi / 2)
    assert b.center == pytest.approx((0.0, 0.0, 0.0)) and _mm([b]) == [(-10, 0, 0)]
    (zx,) = _at(ms, 9)  # G18, J0 allowed
    assert zx.plane == (2, 0, 1) and zx.center == pytest.approx((0.005, 0.0, 0.0))
    assert abs(zx.sweep) == pytest.approx(math.pi)
    (yz,) = _at(ms, 11)
    assert yz.plane == (1, 2, 0) and yz.center == pytest.approx((0.0, 0.0, 0.005))
    assert _mm([yz]) == [(0, 0, 10)]
    (helix,) = _at(ms, 13)  # P2: two turns down to Z-4
    assert helix.sweep == pytest.approx(4 * math.pi) and _mm([helix]) == [(10, 0, -4)]
    (r,) = _at(ms, 14)
    assert -math.pi < r.sweep < 0 and _mm([r]) == [(0, -10.01, -4)]


def test_o_words_return_values_loops_and_functions() -> None:
    ms = _moves('control_flow.ngc')
    assert [p[0] for p in _mm(_at(ms, 14) + _at(ms, 16) + _at(ms, 18))] == [-1, 0, 6]
    assert [p[1] for p in _mm(_at(ms, 23))] == [1, 2, 3]
    assert [p[2] for p in _mm(_at(ms, 35))] == [1, 3, 5]
    assert _mm(_at(ms, 37)) == [(1, 0, 7)]


def test_modal_words_bom_percent_coolant_path_modes_and_units() -> None:
    ms = _moves('modal_words.ngc')
    assert _at(ms, 5)[0].coolant == 'mist'
    (blended,) = _at(ms, 8)
    assert blended.coolant == 'flood+mist' and blended.tolerance == pytest.approx(5e-5)
    assert not blended.exact_stop
    (exact,) = _at(ms, 10)
    assert exact.exact_stop and exact.tolerance == pytest.approx(5e-5)
    (inch,) = _at(ms, 13)
    assert inch.coolant == '' and inch.tolerance is None and not inch.exact_stop
    # LinuxCNC sets F before G20 on a line: 'G20 F10' is 10 mm/min (then shown in inches).
    assert inch.feed == pytest.approx(0.01 / 60) and _mm([inch]) == [(25.4, 1, 1)]
    assert _mm(_at(ms, 15)) == [(9, 1, 1)]
    # M1 (the optional stop on, as LinuxCNC's default switch) and M0 pause; '%' ends it.
    assert [(m.where.line, m.kind, m.pause) for m in ms[-2:]] == [
        (16, 'stop', True),
        (17, 'stop', True),
    ]


def test_the_plan_comes_to_rest_at_the_bottom_of_a_hole() -> None:
    values = {spec.name: spec.default for spec in GcodeTrajectory.PARAMETERS}
    path = GcodeTrajectory.from_parameters(values | {'file': str(PROGRAMS / 'drill_cycles.ngc')})
    # Canned cycles run in exact path mode: the first hole's bottom is reached at rest.
    samples = [path.sample(k * 1e-3) for k in range(int(path.end_time * 1e3))]
    near = [s for s in samples if math.dist(s.position, (0.01, 0.0, -0.005)) < 1e-9]
    assert near and min(math.hypot(*s.velocity) for s in near) < 1e-6


def test_a_tool_missing_from_the_table_is_refused(tmp_path: Path) -> None:
    program = tmp_path / 'part.ngc'
    program.write_text('G21\nT9 M6\nG0 X1\n', encoding='utf-8')
    values = {spec.name: spec.default for spec in GcodeTrajectory.PARAMETERS}
    values |= {'file': str(program), 'tool_table': str(TOOLS)}
    with pytest.raises(ParameterError, match=r'part\.ngc:2:1: tool T9 is not in .*tools\.tbl'):
        GcodeTrajectory.from_parameters(values)
    bad = tmp_path / 'bad.tbl'
    bad.write_text('T1 P1 Z+1\nT2 P2 Q1 W+x\n', encoding='utf-8')
    with pytest.raises(ParameterError, match=r'bad\.tbl:2:10: malformed number'):
        GcodeTrajectory.from_parameters(values | {'tool_table': str(bad)})


def test_cutter_radius_compensation_outside_profile() -> None:
    ms = _moves('fusion_cutter_comp.ngc')  # T1: 6 mm, the tool centre 3 mm left of the path
    z = 24.0  # Z-1 with T1's 25 mm
    # The entry to (0, -5) ends 3 mm left of its direction, cut short where it meets the
    # next move's offset line x = -3 (an inside corner).
    y = -5 + 3 * 2 / math.sqrt(5) + (-3 + 3 / math.sqrt(5)) / 2
    assert _mm(_at(ms, 8)) == [(-3, round(y, 6), z)]
    assert _mm(_at(ms, 9)) == [(-3, 10, z)]
    corner, top = _at(ms, 10)  # an outside corner: round the corner point
    assert corner.kind == 'arc' and corner.center == pytest.approx((0.0, 0.01, z / 1e3))
    assert corner.sweep == pytest.approx(-math.pi / 2) and _mm([corner, top]) == [
        (0, 13, z),
        (15, 13, z),
    ]
    (round_corner,) = _at(ms, 11)  # G2 R5, the tool outside it: R8
    assert round_corner.center == pytest.approx((0.015, 0.005, z / 1e3))
    assert _mm([round_corner]) == [(23, 5, z)] and round_corner.sweep == pytest.approx(-math.pi / 2)
    assert _mm(_at(ms, 12)) == [(23, 0, z)]  # tangent: no corner
    assert _mm(_at(ms, 13)) == [(20, -3, z), (0, -3, z)]
    assert _mm(_at(ms, 14)) == [(-10, -10, z)]  # G40: the exit move to the programmed point
