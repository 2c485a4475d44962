"""A program of segments from the scenario file, run one after the other (ROS-free).

Each entry of the `segments` string array is one segment; targets are absolute [m]:

    "linear X Y Z F"   straight line to (X, Y, Z) at feed F [m/s] (Beltrán 2013 eq. (19)-(22))
    "bezier X Y Z D"   rest-to-rest 8th-order Bézier move to (X, Y, Z) in D [s] (Chávez-Conde §5)
    "dwell D"          hold the current point for D [s]

The program starts at `start` at t = 0; end_time is the sum of the segment durations. Before
t = 0 it holds `start` at rest, from end_time on the last target at rest. Each segment owns
its start instant (right-continuous), t = 0 included: a program that opens with a linear
segment moves at its feed from t = 0 (a cut already under way, as in the force job).

Readings:

- linear: the convention of linear_path.py, i.e. Beltrán 2013 eq. (19)-(22): constant
  velocity (target − current)/duration with duration = distance/F, zero acceleration, so
  the velocity steps at the segment's ends (as in the paper's straight cuts; put a Bézier
  segment before and after for a rest-to-rest cut).
- bezier: exactly BezierRestToRest (bezier.py, which evaluates `blend`) from the current point
  to the target with T1 = segment start, T2 = T1 + D, in the segment's own time; a Bézier
  segment to the current point is a dwell.
- A zero-length linear move (target = current point, to 1e-12 m) is allowed: it takes
  distance/F = 0 s and is dropped from the timeline. It cannot be refused by the `segments`
  check alone, which does not see `start`, and it is harmless.
- Segment boundaries: a linear segment ends exactly at its programmed target; a Bézier
  segment ends where BezierRestToRest ends, F_o + (F_f − F_o)·1, which is the target to
  rounding (~1e-18 m); each segment starts exactly where the previous one ends, and after
  end_time the program holds that last end point. So a one-segment Bézier program is
  BezierRestToRest bit for bit, and the position is continuous to rounding. Velocity is
  continuous except at the ends of linear segments.
- Words are separated by white space, the kind is case-insensitive, numbers are Python
  floats ("1e-3" is fine); NaN and infinities are refused, F and D must be > 0.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import Any, ClassVar

from mill_common.declared import ParamSet, param
from mill_common.parameters import number_list

from mill_trajectory.base import Trajectory, TrajectorySample, box
from mill_trajectory.bezier import BezierParams, BezierRestToRest

Point = tuple[float, float, float]

KINDS = ('linear', 'bezier', 'dwell')
# Number of words of each kind, the kind included.
_WORDS = {'linear': 5, 'bezier': 5, 'dwell': 2}
_USAGE = {
    'linear': '"linear X Y Z F"',
    'bezier': '"bezier X Y Z D"',
    'dwell': '"dwell D"',
}

# The paper's Bézier move (Chávez-Conde §5: 0 → 10 mm in x in 3 s), then a short hold.
DEFAULT_SEGMENTS = ('bezier 0.01 0 0 3.0', 'dwell 0.5')
_ZERO: Point = (0.0, 0.0, 0.0)
# A linear move shorter than this [m] is a zero-length move (rounding, e.g. after a Bézier).
ZERO_LENGTH = 1e-12


@dataclass(frozen=True)
class Segment:
    """One parsed segment: kind, absolute target [m] (None for dwell), feed [m/s] or duration."""

    kind: str
    target: Point | None
    feed: float | None = None  # linear only
    duration: float | None = None  # bezier and dwell


class SegmentError(ValueError):
    """A segment string could not be parsed; str() says which one and why."""


def parse_segment(text: Any, index: int = 0) -> Segment:
    """Parse one segment string; SegmentError names the index and what is wrong."""
    where = f'segment {index}'
    if not isinstance(text, str):
        raise SegmentError(f'{where} must be a string, got {text!r}')
    words = text.split()
    if not words:
        raise SegmentError(f'{where} is empty')
    kind = words[0].lower()
    where = f'segment {index} ({text.strip()!r})'
    if kind not in _WORDS:
        raise SegmentError(
            f'{where}: unknown kind {words[0]!r}, expected one of {", ".join(KINDS)}'
        )
    if len(words) != _WORDS[kind]:
        raise SegmentError(
            f'{where}: {kind} takes {_WORDS[kind] - 1} numbers ({_USAGE[kind]}), '
            f'got {len(words) - 1}'
        )
    numbers: list[float] = []
    for word in words[1:]:
        try:
            value = float(word)
        except ValueError:
            raise SegmentError(f'{where}: {word!r} is not a number') from None
        if not math.isfinite(value):
            raise SegmentError(f'{where}: {word!r} is not a finite number')
        numbers.append(value)
    last = numbers[-1]
    if kind == 'linear':
        if not last > 0.0:
            raise SegmentError(f'{where}: feed F must be > 0 m/s, got {last!r}')
        return Segment('linear', (numbers[0], numbers[1], numbers[2]), feed=last)
    if not last > 0.0:
        raise SegmentError(f'{where}: duration D must be > 0 s, got {last!r}')
    if kind == 'bezier':
        return Segment('bezier', (numbers[0], numbers[1], numbers[2]), duration=last)
    return Segment('dwell', None, duration=last)


def parse_segments(texts: Any) -> tuple[Segment, ...]:
    """Parse a list of segment strings; SegmentError on the first bad one."""
    if not isinstance(texts, list | tuple):
        raise SegmentError('must be a list of segment strings')
    if not texts:
        raise SegmentError('must list at least one segment')
    return tuple(parse_segment(text, i) for i, text in enumerate(texts))


def _segments_check(value: Any) -> str | None:
    try:
        parse_segments(value)
    except SegmentError as exc:
        return str(exc)
    return None


@dataclass(frozen=True)
class _Piece:
    """A segment placed on the timeline: starts at t0 from p0, lasts `duration`."""

    kind: str
    t0: float
    duration: float
    p0: Point
    p1: Point  # where the next segment starts, and the hold after the last one
    velocity: Point  # linear only
    bezier: BezierRestToRest | None  # bezier only


@dataclass(frozen=True)
class ProgramParams(ParamSet):
    """A program of segments from a start point."""

    PREFIX: ClassVar[str] = 'program'
    start: list[float] = param(
        [0.0, 0.0, 0.0], 'start point x, y, z at t = 0', number_list(3), unit='m'
    )
    segments: list[str] = param(
        list(DEFAULT_SEGMENTS),
        'segments run in order, one string each, absolute targets [m]: '
        '"linear X Y Z F" (feed F [m/s]), "bezier X Y Z D" (rest-to-rest in D [s]), '
        '"dwell D" (hold D [s])',
        _segments_check,
    )


class ProgramTrajectory(Trajectory):
    """Segments (linear / bezier / dwell) from `start`, one after the other, from t = 0."""

    PARAMS: ClassVar[type[ProgramParams]] = ProgramParams

    def __init__(self, params: ProgramParams = ProgramParams()) -> None:
        """Build the timeline (the set has checked start and segments)."""
        start = params.start
        self.start: Point = (start[0], start[1], start[2])
        self.segments: tuple[Segment, ...] = parse_segments(params.segments)
        self._pieces: list[_Piece] = []
        t = 0.0
        here = self.start
        for seg in self.segments:
            piece = self._place(seg, t, here)
            if piece is None:  # zero-length linear move: 0 s, dropped
                here = seg.target  # type: ignore[assignment]
                continue
            self._pieces.append(piece)
            here = piece.p1
            t += piece.duration
        self._starts = [p.t0 for p in self._pieces]
        self.end_point: Point = here
        self.end_time: float = t

    @staticmethod
    def _place(seg: Segment, t0: float, p0: Point) -> _Piece | None:
        if seg.kind == 'linear':
            assert seg.target is not None and seg.feed is not None
            length = math.dist(p0, seg.target)
            if length <= ZERO_LENGTH:
                return None
            # Beltrán 2013 eq. (19)-(22): t_f − t_i = length/F, velocity (p_f − p_i)/(t_f − t_i)
            duration = length / seg.feed
            v = tuple((b - a) / duration for a, b in zip(p0, seg.target, strict=True))
            return _Piece('linear', t0, duration, p0, seg.target, v, None)  # type: ignore[arg-type]
        assert seg.duration is not None
        if seg.kind == 'bezier':
            assert seg.target is not None
            move = BezierRestToRest(
                BezierParams(start=list(p0), end=list(seg.target), t1=0.0, t2=seg.duration)
            )
            # Ends where the Bézier formula ends, F_o + (F_f − F_o)·1 (= target to rounding).
            p1 = move.sample(seg.duration).position
            return _Piece('bezier', t0, seg.duration, p0, p1, _ZERO, move)
        return _Piece('dwell', t0, seg.duration, p0, p0, _ZERO, None)

    @property
    def boundaries(self) -> tuple[float, ...]:
        """Start time of every (non-empty) segment, then end_time [s]."""
        return (*self._starts, self.end_time)

    def sample(self, t: float) -> TrajectorySample:
        if t < 0.0 or not self._pieces:
            return TrajectorySample(self.start, _ZERO, _ZERO)
        if t >= self.end_time:
            return TrajectorySample(self.end_point, _ZERO, _ZERO)
        piece = self._pieces[bisect.bisect_right(self._starts, t) - 1]
        tau = t - piece.t0
        if piece.kind == 'bezier':
            assert piece.bezier is not None
            # Chávez-Conde §5: F*(t) = F_o + (F_f − F_o) ψ(Δ), Δ = (t − T1)/(T2 − T1)
            return piece.bezier.sample(tau)
        p0 = piece.p0
        if piece.kind == 'linear':
            v = piece.velocity
            # Beltrán 2013 eq. (19)-(22): p(t) = (p_f − p_i)/(t_f − t_i) (t − t_i) + p_i
            pos = (p0[0] + v[0] * tau, p0[1] + v[1] * tau, p0[2] + v[2] * tau)
            return TrajectorySample(pos, v, _ZERO)
        return TrajectorySample(p0, _ZERO, _ZERO)

    def bounds(self, step: float) -> tuple[Point, Point]:
        # linear moves, monotone Bézier blends and dwells all stay between their ends
        return box([self.start, *(p for piece in self._pieces for p in (piece.p0, piece.p1))])
