"""ProgramTrajectory: segment timing, continuity, Bézier identity, dwell, parse errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mill_common.parameters import ParameterError, algorithm_specs, validate
from mill_trajectory.bezier import BezierParams, BezierRestToRest
from mill_trajectory.config import build_job, parameter_specs
from mill_trajectory.linear_path import LinearParams, LinearPath
from mill_trajectory.program import ProgramParams, ProgramTrajectory, parse_segment
from mill_trajectory.registry import TRAJECTORIES

ZERO = (0.0, 0.0, 0.0)

MIXED = [
    'bezier 0.01 0.002 -0.001 1.5',
    'linear 0.02 0.002 -0.001 0.004',
    'dwell 0.25',
    'LINEAR  0.02 -0.01 -0.003 3e-3',
    'bezier 0 0 0 2',
]


def _program(segments: list[str], start=(0.0, 0.0, 0.0)) -> ProgramTrajectory:
    return ProgramTrajectory.from_parameters({'start': list(start), 'segments': segments})


def test_defaults() -> None:
    path = ProgramTrajectory.from_parameters({})
    assert path.end_time == 3.5
    assert path.sample(3.0).position == pytest.approx((0.01, 0.0, 0.0), abs=1e-15)
    assert path.sample(3.2) == path.sample(10.0)
    assert path.sample(10.0).position == (0.01, 0.0, 0.0)


def test_one_bezier_segment_is_bezier_rest_to_rest_exactly() -> None:
    start, end = (0.003, -0.02, 0.001), (0.013, 0.005, -0.004)
    path = _program(['bezier 0.013 0.005 -0.004 2.5'], start)
    ref = BezierRestToRest(BezierParams(start=start, end=end, t1=0.0, t2=2.5))
    assert path.end_time == ref.end_time
    for t in np.linspace(-0.5, 3.0, 3501):
        assert path.sample(float(t)) == ref.sample(float(t)), t


def test_end_time_and_linear_duration_is_distance_over_feed() -> None:
    path = _program(MIXED)
    p1 = (0.01, 0.002, -0.001)
    p2 = (0.02, 0.002, -0.001)
    p3 = (0.02, -0.01, -0.003)
    d2 = math.dist(p1, p2) / 0.004
    d4 = math.dist(p2, p3) / 3e-3
    assert d2 == pytest.approx(2.5)
    expected = [0.0, 1.5, 1.5 + d2, 1.75 + d2, 1.75 + d2 + d4, 3.75 + d2 + d4]
    assert path.boundaries == pytest.approx(expected, rel=1e-15)
    assert path.end_time == pytest.approx(3.75 + d2 + d4, rel=1e-15)
    # Linear segments move at the feed with zero acceleration.
    s = path.sample(1.5 + 0.5 * d2)
    assert math.hypot(*s.velocity) == pytest.approx(0.004, rel=1e-12)
    assert s.acceleration == ZERO
    assert s.position == pytest.approx((0.015, 0.002, -0.001), abs=1e-15)
    s = path.sample(1.75 + d2 + 0.3 * d4)
    assert math.hypot(*s.velocity) == pytest.approx(3e-3, rel=1e-12)
    # Same convention as LinearPath on the same straight line.
    line = LinearPath(LinearParams(waypoints=[*p1, *p2], feed_rate=0.004, start_time=1.5))
    for t in np.linspace(1.5, 1.5 + d2, 101)[1:-1]:  # LinearPath is at rest at its ends
        a, b = path.sample(float(t)), line.sample(float(t))
        assert a.position == pytest.approx(b.position, abs=1e-16)
        assert a.velocity == pytest.approx(b.velocity, abs=1e-16)


def test_position_is_continuous_at_boundaries() -> None:
    path = _program(MIXED, start=(0.0, 0.0, 0.0))
    assert path.sample(-1.0) == path.sample(0.0)
    assert path.sample(0.0).position == ZERO
    for tb in path.boundaries:
        for eps in (1e-9, 1e-12):
            before = path.sample(tb - eps).position
            after = path.sample(tb + eps).position
            # 1 nm/s·eps: at most the feed times eps, plus rounding.
            assert before == pytest.approx(after, abs=0.005 * eps + 1e-15), tb
        at = path.sample(tb).position
        assert at == pytest.approx(path.sample(tb - 1e-12).position, abs=1e-14)
    # Every programmed target is reached.
    ends = path.boundaries[1:]
    targets = [(0.01, 0.002, -0.001), (0.02, 0.002, -0.001), None, (0.02, -0.01, -0.003), ZERO]
    for tb, target in zip(ends, targets, strict=True):
        if target is not None:
            assert path.sample(tb).position == pytest.approx(target, abs=1e-15)
    assert path.sample(path.end_time + 1.0) == path.sample(path.end_time)
    final = path.sample(path.end_time + 1.0)
    assert final.position == ZERO
    assert final.velocity == final.acceleration == ZERO


def test_dwell_holds() -> None:
    path = _program(['linear 0.003 0 0 0.003', 'dwell 2.0', 'bezier 0.003 0.01 0 1'])
    for t in np.linspace(1.0, 3.0, 201)[1:-1]:
        s = path.sample(float(t))
        assert s.position == (0.003, 0.0, 0.0)
        assert s.velocity == s.acceleration == ZERO
    assert path.end_time == pytest.approx(4.0)
    # A Bézier segment starts and ends at rest.
    assert path.sample(3.0 + 1e-6).velocity == pytest.approx(ZERO, abs=1e-30)


def test_zero_length_linear_takes_no_time() -> None:
    path = _program(['linear 0 0 0 0.01', 'dwell 1', 'linear 0.01 0 0 0.01', 'linear 0.01 0 0 1'])
    assert path.end_time == pytest.approx(2.0)
    assert len(path.boundaries) == 3  # dwell, one linear move, end
    assert path.sample(5.0).position == (0.01, 0.0, 0.0)


def test_registered_and_built_from_node_values() -> None:
    assert TRAJECTORIES['program'] is ProgramTrajectory
    values = {name: spec.default for name, spec in parameter_specs()}
    values['trajectory'] = 'program'
    values['program.segments'] = ['linear 0.01 0 0 0.005', 'dwell 1']
    job = build_job(values)
    assert isinstance(job.trajectory, ProgramTrajectory)
    assert job.end_time == pytest.approx(3.0)
    names = dict(algorithm_specs([ProgramTrajectory]))
    assert set(names) == {'program.start', 'program.segments'}


@pytest.mark.parametrize(
    ('segments', 'words'),
    [
        (['bezier 0.01 0 0 3', 'circle 0 0 0 1'], ['segment 1', "unknown kind 'circle'"]),
        (['linear 0.01 0 0'], ['segment 0', 'takes 4 numbers', 'got 3']),
        (['dwell'], ['segment 0', 'takes 1 numbers', 'got 0']),
        (['dwell 1 2'], ['segment 0', 'got 2']),
        (['dwell 1', 'bezier 0.01 0 0 3 4'], ['segment 1', 'got 5']),
        (['linear 0.01 0 x 0.1'], ['segment 0', "'x' is not a number"]),
        (['linear 0.01 0 nan 0.1'], ['segment 0', 'not a finite number']),
        (['bezier inf 0 0 1'], ['segment 0', 'not a finite number']),
        (['linear 0.01 0 0 0'], ['segment 0', 'feed F must be > 0']),
        (['linear 0.01 0 0 -0.1'], ['segment 0', 'feed F must be > 0']),
        (['dwell 1', 'dwell 0'], ['segment 1', 'duration D must be > 0']),
        (['bezier 0.01 0 0 -3'], ['segment 0', 'duration D must be > 0']),
        (['dwell 1', '   '], ['segment 1', 'is empty']),
        (['dwell 1', 3.0], ['segment 1', 'must be a string']),
        ([], ['at least one segment']),
        ('dwell 1', ['must be a list']),
    ],
)
def test_parse_errors(segments, words: list[str]) -> None:
    with pytest.raises(ParameterError) as info:
        ProgramTrajectory.from_parameters({'segments': segments})
    assert info.value.name == 'program.segments'
    for word in words:
        assert word in info.value.reason, info.value.reason
    # The node's own check refuses the same value with the same reason.
    spec = next(s for s in ProgramTrajectory.PARAMETERS if s.name == 'segments')
    with pytest.raises(ParameterError, match=r'program\.segments'):
        validate(spec, segments, 'program.segments')


def test_bad_start_is_refused() -> None:
    with pytest.raises(ParameterError) as info:
        ProgramTrajectory.from_parameters({'start': [0.0, 0.0]})
    assert info.value.name == 'program.start'
    with pytest.raises(ParameterError):
        ProgramTrajectory(ProgramParams(start=(0.0, math.nan, 0.0)))


def test_parse_segment_fields() -> None:
    seg = parse_segment(' Bezier  1e-3 -2 0.5   3 ', 4)
    assert (seg.kind, seg.target, seg.duration, seg.feed) == (
        'bezier',
        (1e-3, -2.0, 0.5),
        3.0,
        None,
    )
    seg = parse_segment('linear 1 2 3 0.5')
    assert (seg.kind, seg.target, seg.feed) == ('linear', (1.0, 2.0, 3.0), 0.5)
    seg = parse_segment('dwell 0.25')
    assert (seg.kind, seg.target, seg.duration) == ('dwell', None, 0.25)


def test_linear_to_the_target_of_a_bezier_is_zero_length() -> None:
    start = (0.003, -0.02, 0.001)
    path = _program(['bezier 0.013 0.005 -0.004 2.5', 'linear 0.013 0.005 -0.004 0.01'], start)
    assert path.end_time == 2.5
    assert path.sample(3.0).position == (0.013, 0.005, -0.004)
