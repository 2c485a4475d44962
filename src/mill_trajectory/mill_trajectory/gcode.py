"""An RS274/NGC (G-code) part program read into moves in machine coordinates [m]. ROS-free.

The words and their meaning follow LinuxCNC (docs/user-guide.md, "G-code programs", has the
table). Defaults at the start: G21 G90 G91.1 G17 G54 G40 G49 G64 G94 G98 G80, spindle and
coolant off, tool 0, no feed, no spindle speed.

Machine position = program position + work offset (G54..G59.3) + G92/G52 offset + tool
length offset (G43). G53 moves and G28/G30 land on machine positions.

The spindle is a signed speed [rev/min]: S for M3, -S for M4, 0 off. Where it changes (M3,
M4, M5, or a new S while it runs) the program has a `spindle` move: the axes come to rest,
and the spindle takes its new speed there (a CNC waits for its spindle as well). A tool
change (M6) is a `stop` with a message (the machine is taken to have a changer: the program
goes on). M0, and M1 with the optional stop switch on (Setup.optional_stop, LinuxCNC's
default), are a `stop` that pauses: the trajectory holds there until the operator resumes
(mill_trajectory.hold). "(MSG, text)", "(DEBUG, text)" and "(PRINT, text)" are `message`
moves (nothing moves). Coolant (M7 mist, M8 flood, M9 off)
and the path tolerance (G64 P) are carried by each move; G61/G61.1 mark moves that end at
rest. Between G41/G42 and G40 the moves are offset to the tool's centre
(mill_trajectory.gcode_comp).

Within a line the words act in LinuxCNC's order: messages, F (read in the units in force
before the line's G20/G21, kept in m/s), S, T, M6, M3/M4/M5, M7/M8/M9, G4, plane, units,
G40, G43/G49, coordinate system, path mode, distance modes, retract mode, G10/G28/G30/G52/
G92, the motion (G0..G3, canned cycles, as modified by G53), then M0/M1/M2/M30.

Nothing is half-read: the first problem raises GcodeError 'file:line:column: what', and no
move is returned.
"""

from __future__ import annotations

from pathlib import Path

from mill_trajectory.gcode_flow import Program
from mill_trajectory.gcode_state import Setup, State, Tool
from mill_trajectory.gcode_tools import read_tool_table
from mill_trajectory.gcode_words import Move, Point, read_file

# The interpreter's public names: the program readers here, the setup and the tool table.
__all__ = ['Setup', 'Tool', 'parse_program', 'read_program', 'read_tool_table']


def read_program(
    path: str | Path,
    start: Point,
    work_offset: Point = (0.0, 0.0, 0.0),
    setup: Setup | None = None,
) -> list[Move]:
    """Read a G-code file; the tool stands at `start` (machine coordinates [m])."""
    text = read_file(path, 'utf-8', 'G-code')
    return parse_program(text, str(path), start, work_offset, setup)


def parse_program(
    text: str,
    file: str,
    start: Point,
    work_offset: Point = (0.0, 0.0, 0.0),
    setup: Setup | None = None,
) -> list[Move]:
    """The moves of a program's text (see the module doc). work_offset is G54's, and
    replaces setup's."""
    setup = setup or Setup()
    offsets = [list(p) for p in setup.work_offsets] + [[0.0, 0.0, 0.0]] * 9
    offsets[0] = [float(v) for v in work_offset]
    state = State(here=tuple(map(float, start)), setup=setup)  # type: ignore[arg-type]
    state.systems = [list(map(float, p)) for p in offsets[:9]]
    return Program(text.removeprefix('\ufeff'), file, state).run()
