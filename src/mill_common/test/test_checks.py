"""Input checks: bad messages become one-line rejections, never exceptions."""

from __future__ import annotations

import math

import pytest
from mill_common.checks import (
    FOREIGN,
    REFERENCE_LEAD_NS,
    DropCounter,
    Rejected,
    Sender,
    StampCheck,
    ahead,
    axis_points,
    joint_values,
    owner_check,
    point_values,
)
from mill_common.watch import InputWatch, Level


def arrays(**kw):
    base = {'position': [], 'velocity': [], 'effort': []}
    base.update(kw)
    return base


def test_joint_values_of_a_good_message() -> None:
    assert joint_values(['y', 'x'], arrays(position=[1.0, 2.0]), 'x', ['position']) == (2.0,)


@pytest.mark.parametrize(
    ('names', 'values', 'reason'),
    [
        (['w'], arrays(effort=[1.0]), "no joint 'x'"),
        ([], arrays(effort=[1.0]), "no joint 'x'"),
        (['x'], arrays(effort=[]), 'effort has 0 entries'),
        (['y', 'x'], arrays(effort=[1.0]), 'needs 2'),
        (['x'], arrays(effort=[math.nan]), 'is nan'),
        (['x'], arrays(effort=[-math.inf]), 'is -inf'),
    ],
)
def test_joint_values_rejects(names, values, reason) -> None:
    out = joint_values(names, values, 'x', ['effort'])
    assert isinstance(out, Rejected) and reason in out.reason
    # Only a value that is there and not finite is `non_finite` (a command's brake request).
    assert out.non_finite == (reason.startswith('is '))


def test_point_values() -> None:
    point = {'positions': [1.0, 2.0, 3.0], 'velocities': [], 'accelerations': [0.1, 0.2, 0.3]}
    out = point_values(
        ['x', 'y', 'z'], point, ['z', 'x'], ['positions'], ['velocities', 'accelerations']
    )
    assert out == {
        'positions': (3.0, 1.0),
        'velocities': (0.0, 0.0),
        'accelerations': (0.3, 0.1),
    }
    short = dict(point, positions=[1.0, 2.0])
    assert (
        'positions has 2 entries'
        in point_values(['x', 'y', 'z'], short, ['x'], ['positions']).reason
    )
    bad = dict(point, accelerations=[0.1, math.nan, 0.3])
    got = point_values(['x', 'y', 'z'], bad, ['y'], ['positions'], ['accelerations'])
    assert isinstance(got, Rejected) and 'nan' in got.reason
    assert "no joint 'w'" in point_values(['x'], point, ['w'], ['positions']).reason


class Point:
    def __init__(self, positions, velocities=(), accelerations=()) -> None:
        self.positions, self.velocities, self.accelerations = positions, velocities, accelerations


@pytest.mark.parametrize(
    'point',
    [
        Point([1.0, 2.0, 3.0], [], [0.1, 0.2, 0.3]),
        Point([1.0, 2.0, 3.0], [4.0, 5.0, 6.0]),
        Point([1.0, 2.0]),
        Point([1.0, math.inf, 3.0]),
        Point([1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [0.1, math.nan, 0.3]),
        Point([1.0, 2.0, 3.0], [4.0]),
    ],
)
@pytest.mark.parametrize('joint', ['x', 'y', 'w'])
def test_axis_points_reads_each_point_as_point_values_does(point, joint) -> None:
    names = ['x', 'y', 'z']
    one = point_values(names, vars(point), [joint], ['positions'], ['velocities', 'accelerations'])
    got = axis_points(names, [point, point], joint)
    if isinstance(one, Rejected):
        assert isinstance(got, Rejected)
        assert got.reason.split(' ')[:2] == one.reason.split(' ')[:2]
    else:
        expected = (one['positions'][0], one['velocities'][0], one['accelerations'][0])
        assert got == [expected, expected]


def test_stamp_check_in_lockstep() -> None:
    check = StampCheck(period_ns=1_000_000)
    assert check.check(2_000_000) is None
    check.accept(2_000_000)
    assert 'off the sample grid' in check.check(2_500_000).reason
    assert 'in the past' in check.check(1_000_000).reason
    assert check.check(2_000_000) is None and check.is_repeat(2_000_000)
    assert check.check(3_000_000) is None and not check.is_repeat(3_000_000)
    assert 'negative' in check.check(-1).reason


def test_stamp_check_in_real_time_has_no_grid() -> None:
    check = StampCheck(period_ns=None)
    assert check.check(1_234_567) is None
    check.accept(1_234_567)
    assert check.check(1_234_568) is None
    assert 'in the past' in check.check(1_000_000).reason


def test_ahead_of_the_plant() -> None:
    T = 1_000_000
    assert ahead(5 * T, None, T) is None  # no state yet: a (re)starting node takes anything
    assert ahead(5 * T, 4 * T, T) is None  # the next step
    assert ahead(4 * T, 4 * T, T) is None
    got = ahead(6 * T, 4 * T, T)
    assert isinstance(got, Rejected) and 'ahead of the plant' in got.reason
    assert ahead(4 * T + REFERENCE_LEAD_NS, 4 * T, REFERENCE_LEAD_NS) is None
    assert ahead(4 * T + REFERENCE_LEAD_NS + T, 4 * T, REFERENCE_LEAD_NS) is not None


def test_owner() -> None:
    assert owner_check('x_controller', 'x_controller') is None
    assert owner_check('', '') is None
    assert 'not by its owner' in owner_check('intruder', 'x_controller').reason
    assert 'unnamed publisher' in owner_check('', 'x_controller').reason


def test_drop_counter_rate_limits_reports() -> None:
    drops = DropCounter(interval=1.0)
    r = Rejected('bad')
    assert drops.drop('a', r, 0.0)
    assert not drops.drop('a', r, 0.5)
    assert drops.drop('b', r, 0.6)  # per input
    assert drops.drop('a', r, 1.0)
    assert drops.counts == {'a': 3, 'b': 1} and drops.total == 4


def test_input_watch_levels_and_outages() -> None:
    w = InputWatch('/mill/x/state', 'plant', warn_after=1.0, error_after=5.0)
    assert w.waiting and w.level(100.0) is Level.OK  # before the first message: waiting
    assert 'nothing yet' in w.describe(100.0)
    assert w.heard(0.0) is None
    assert w.level(0.5) is Level.OK
    assert w.level(1.0) is Level.WARN
    assert w.level(5.0) is Level.ERROR
    assert 'for 2.0 s' in w.describe(2.0)
    assert w.heard(2.0) == pytest.approx(2.0)  # the outage ends, with its length
    assert w.heard(2.5) is None
    assert w.outages == 1 and w.last_outage == pytest.approx(2.0)


def test_a_sender_is_called_by_the_graphs_name_and_what_it_wrote() -> None:
    assert Sender(FOREIGN, '/rogue').called('x_controller') == "/rogue (frame_id 'x_controller')"
    assert Sender(FOREIGN, '/rogue').called('') == "/rogue (frame_id '')"
    assert Sender(FOREIGN, '').called('x_controller') == 'x_controller'  # the graph names none
    assert Sender(FOREIGN, '').called('') == '(unnamed)'
