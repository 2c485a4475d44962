"""A G-code part program, checked and planned whole before anything moves. ROS-free.

`trajectory: gcode` with `gcode.file: part.ngc`: the file is read (mill_trajectory.gcode),
its arcs cut into chords (mill_trajectory.toolpath), its path checked against the machine's
travel (the trajectory node's travel.min / travel.max), and the feed planned within the
per-axis limits and the path tolerance (mill_trajectory.planner). Any problem is one line
'file:line:column: what'.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any, ClassVar

from mill_common.declared import ParamSet, param
from mill_common.parameters import (
    ParameterError,
    boolean,
    non_negative,
    number_list,
    positive,
)

from mill_trajectory.base import Trajectory, TrajectorySample
from mill_trajectory.feed_report import block_feeds, feed_summary, pieces_by_block
from mill_trajectory.gcode import Setup, read_program, read_tool_table
from mill_trajectory.gcode_words import GcodeError, Move
from mill_trajectory.hold import MESSAGE, PAUSE, TOOL_CHANGE, ProgramEvent
from mill_trajectory.override_limit import RESERVE, OverrideLimit
from mill_trajectory.planner import Limits, Piece, PlanError, PlannedPath, plan, xyz
from mill_trajectory.toolpath import Travel, check_travel

# A small machine (the Beltrán 2013 axes: 3.175 mm pitch screws, 10 N·m): 3 m/min,
# 0.5 m/s², 10 m/s³ per axis, corners within 0.01 mm.
DEFAULT_VELOCITY = [0.05, 0.05, 0.05]
DEFAULT_ACCELERATION = [0.5, 0.5, 0.5]
DEFAULT_JERK = [10.0, 10.0, 10.0]
DEFAULT_TOLERANCE = 1e-5
WIDE_TRAVEL = Travel((-math.inf, -math.inf, -math.inf), (math.inf, math.inf, math.inf))


def _limit(value: Any) -> str | None:
    """Three numbers >= 0 (0: no limit)."""
    reason = number_list(3)(value)
    if reason:
        return reason
    return 'must be >= 0 (0: no limit)' if any(v < 0 for v in value) else None


def _positive3(value: Any) -> str | None:
    reason = number_list(3)(value)
    if reason:
        return reason
    return 'must be > 0' if any(not v > 0 for v in value) else None


def _file(value: Any) -> str | None:
    return None if isinstance(value, str) and value.strip() else 'must name a G-code file'


def _text(value: Any) -> str | None:
    return None if isinstance(value, str) else 'must be a string'


def _offsets(value: Any) -> str | None:
    return number_list(24)(value)


@dataclass(frozen=True)
class GcodeParams(ParamSet):
    """The part program and the machine's limits it is planned within."""

    PREFIX: ClassVar[str] = 'gcode'
    file: str = param('part.ngc', 'the G-code (RS274/NGC) part program to run', _file)
    start: list[float] = param(
        [0.0, 0.0, 0.0],
        'where the tool stands when the program starts',
        number_list(3),
        unit='m',
    )
    work_offset: list[float] = param(
        [0.0, 0.0, 0.0],
        'G54 work offset: machine position of the program zero x, y, z',
        number_list(3),
        unit='m',
    )
    work_offsets: list[float] = param(
        [0.0] * 24,
        'G55, G56, G57, G58, G59, G59.1, G59.2, G59.3 work offsets: x, y, z of each program '
        'zero, one after the other (24 numbers); G10 L2/L20 may change them',
        _offsets,
        unit='m',
    )
    home: list[float] = param(
        [0.0, 0.0, 0.0],
        'the G28 position, machine coordinates (LinuxCNC #5161-5163)',
        number_list(3),
        unit='m',
    )
    home2: list[float] = param(
        [0.0, 0.0, 0.0],
        'the G30 position, machine coordinates (LinuxCNC #5181-5183)',
        number_list(3),
        unit='m',
    )
    tool_table: str = param(
        '',
        'LinuxCNC tool table file (lines "T1 P1 Z+12.5 D6.0 ;comment", lengths in mm) for T, '
        'M6 and G43 H; empty: no table, every tool has zero offsets',
        _text,
    )
    max_velocity: list[float] = param(
        DEFAULT_VELOCITY, 'per-axis velocity limit', _positive3, unit='m/s'
    )
    max_acceleration: list[float] = param(
        DEFAULT_ACCELERATION,
        'per-axis acceleration limit [m/s^2]; 0 = none (the velocity steps at corners)',
        _limit,
    )
    max_jerk: list[float] = param(DEFAULT_JERK, 'per-axis jerk limit [m/s^3]; 0 = none', _limit)
    optional_stop: bool = param(
        True,
        "M1 pauses as M0 does (LinuxCNC's optional-stop switch, on); false: M1 does nothing",
        boolean,
    )
    resume_after: float = param(
        0.0,
        'a pause (M0, M1) ends by itself after this long at rest [s], for unattended runs '
        "and the offline simulator; 0 = it holds until the trajectory's ~/resume is called",
        non_negative,
        unit='s',
    )
    tolerance: float = param(
        DEFAULT_TOLERANCE,
        'path tolerance: how far a blended corner or an arc chord may leave the '
        'programmed path [m] (as LinuxCNC G64 P)',
        positive,
    )


class GcodeTrajectory(Trajectory):
    """The planned path of a G-code file (see the module doc).

    Built from its plan, not from its set: from_parameters reads and plans the program.
    """

    PARAMS: ClassVar[type[GcodeParams]] = GcodeParams

    def __init__(
        self,
        planned: PlannedPath,
        override_limit: OverrideLimit | None = None,
        events: tuple[ProgramEvent, ...] = (),
        resume_after: float = 0.0,
    ) -> None:
        self.planned = planned
        # The program's messages, pauses and tool changes at the path time their line runs.
        self.events = events
        self.pauses = tuple(e for e in events if e.kind == PAUSE)
        self.resume_after = resume_after  # gcode.resume_after [s]; 0: wait for ~/resume
        self.moves: tuple[Move, ...] = ()  # the program read (from_parameters)
        self.tolerance = DEFAULT_TOLERANCE  # the path tolerance it was planned with [m]
        self.end_time = planned.end_time
        # How fast a feed override may change on it (None: no override, or no limit binds).
        self.override_limit = override_limit
        # 'feed held: N % of F on arcs, M % on lines' (mill_trajectory.feed_report), for
        # the run's summary; '' unless read from a program.
        self.feed_summary = ''

    @classmethod
    def from_parameters(
        cls,
        values: Mapping[str, Any],
        travel: Travel = WIDE_TRAVEL,
        override_max: float | None = None,
    ) -> GcodeTrajectory:
        """Read, check and plan; ParameterError('file', ...) with 'file:line:column: what'.

        With a feed override (override_max: its maximum) the plan leaves the override room to
        reach its maximum, and to change (mill_trajectory.override_limit)."""
        v = GcodeParams.from_values(values)
        machine = machine_limits(v)
        limits, override_limit = machine, None
        if override_max is not None:
            o = max(override_max, 1.0)
            limits = machine.scaled(o, RESERVE)
            override_limit = OverrideLimit.of(
                machine.velocity, machine.acceleration, machine.jerk, o
            )
        try:
            setup = gcode_setup(v)
        except GcodeError as exc:
            raise ParameterError('tool_table', v.tool_table, str(exc)) from None
        try:
            moves = read_program(v.file, xyz(v.start), xyz(v.work_offset), setup)
            # The planner has one path tolerance: the tightest of the machine's and the
            # program's G64 P (arc chords take each move's own, toolpath.pieces_of).
            tolerances = [m.tolerance for m in moves if m.tolerance]
            limits = replace(limits, tolerance=min([limits.tolerance, *tolerances]))
            pieces, blocks = pieces_by_block(moves, limits.tolerance)
            check_travel(pieces, [moves[b].where for b in blocks], travel)
            planned = plan(pieces, limits)
        except (GcodeError, PlanError) as exc:
            raise ParameterError('file', v.file, str(exc)) from None
        events = program_events(moves, pieces, blocks, planned)
        out = cls(planned, override_limit, events, v.resume_after)
        out.moves, out.tolerance = tuple(moves), limits.tolerance  # for a preview
        out.feed_summary = feed_summary(block_feeds(moves, pieces, blocks, planned))
        return out

    def sample(self, t: float) -> TrajectorySample:
        return self.planned.sample(t)


def gcode_setup(v: GcodeParams) -> Setup:
    """The machine side of a program from its parameters (GcodeError: a bad tool table)."""
    table = v.tool_table.strip()
    others = v.work_offsets
    return Setup(
        work_offsets=((0.0, 0.0, 0.0), *(xyz(others[i : i + 3]) for i in range(0, 24, 3))),
        home=xyz(v.home),
        home2=xyz(v.home2),
        tools=read_tool_table(table) if table else None,
        tool_table=table,
        optional_stop=v.optional_stop,
    )


def machine_limits(v: GcodeParams) -> Limits:
    """The per-axis limits and the path tolerance the planner keeps (0: no limit)."""
    return Limits(
        xyz(v.max_velocity),
        xyz([a if a > 0 else math.inf for a in v.max_acceleration]),
        xyz([j if j > 0 else math.inf for j in v.max_jerk]),
        v.tolerance,
    )


def program_events(
    moves: Sequence[Move], pieces: Sequence[Piece], blocks: Sequence[int], planned: PlannedPath
) -> tuple[ProgramEvent, ...]:
    """The program's messages, pauses and tool changes, each at the path time its line runs:
    a message where the next piece begins (so one before a stop shows once at rest), a
    pause or a tool change when the reference has come to rest for it."""
    starts = planned.piece_starts(pieces)
    out: list[ProgramEvent] = []
    k = 0  # the first piece of the move at hand or after it
    for b, m in enumerate(moves):
        while k < len(blocks) and blocks[k] < b:
            k += 1
        if not m.message:
            continue
        t = starts[k] if k < len(starts) else planned.end_time
        if m.kind == 'message':
            out.append(ProgramEvent(t, MESSAGE, str(m.where), m.message, m.channel))
        elif m.kind == 'stop':
            kind = PAUSE if m.pause else TOOL_CHANGE
            out.append(ProgramEvent(t, kind, str(m.where), m.message))
    return tuple(out)
