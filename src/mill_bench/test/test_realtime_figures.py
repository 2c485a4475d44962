"""benchmark --realtime: when a rate holds, and the highest rate a case holds."""

from __future__ import annotations

import math
from typing import Any

import pytest
from mill_bench.realtime_figures import RatePoint, first_failed, highest_held

AXES = ('x', 'y', 'z')


def point(
    rate: float = 500.0,
    late: float = 0.0,
    run: float = 0.0,
    p99: float = 0.5,
    overruns: int = 0,
    case: str = 'single',
    worst_axis: str = 'y',
) -> RatePoint:
    """Good figures on every axis but `worst_axis`, which has the ones given."""
    good = {
        'late_fraction': 0.0,
        'longest_late_run': 0.0,
        'latency_median_ms': 0.3,
        'latency_p99_ms': 0.4,
        'latency_max_ms': 0.9,
    }
    bad = {
        **good,
        'late_fraction': late,
        'longest_late_run': run,
        'latency_p99_ms': p99,
        'latency_median_ms': 0.35,
    }
    drive = {a: bad if a == worst_axis else good for a in AXES}
    return RatePoint(case, rate, drive, overruns, ticks=1000)


def test_good_figures_hold() -> None:
    p = point()
    assert p.holds and p.failed() == []
    assert (p.late_fraction, p.latency_p99_ms, p.latency_median_ms) == (0.0, 0.5, 0.35)


@pytest.mark.parametrize(
    ('figures', 'missed'),
    [
        ({'late': 0.0049}, []),
        ({'late': 0.005}, ['no command']),  # 0.5 % of the ticks: not below
        ({'p99': 0.999}, []),
        ({'p99': 1.0}, ['p99']),
        ({'run': 2.0}, []),
        ({'run': 3.0}, ['in a row']),
        ({'overruns': 9}, []),
        ({'overruns': 10}, ['late ticks']),  # 10 of 1000: 1 %
        (
            {'late': 0.2, 'run': 43.0, 'p99': 112.0, 'overruns': 85},
            ['no command', 'p99', 'in a row', 'late ticks'],
        ),
    ],
)
def test_each_part_of_the_criterion_on_the_worst_axis(
    figures: dict[str, Any], missed: list[str]
) -> None:
    p = point(**figures)
    assert p.failed() == missed
    assert p.holds == (not missed)


def test_a_figure_the_drive_could_not_give_does_not_hold() -> None:
    # NaN: no command came at all on an axis (the drive reports NaN), or no run happened
    assert point(late=math.nan).failed() == ['no command']
    assert point(p99=math.nan).failed() == ['p99']
    failed = RatePoint('processes', 250.0, {}, 0, 0, notes=('the run failed: ...',))
    assert failed.failed() == ['no command', 'p99', 'in a row', 'late ticks']
    assert math.isnan(failed.late_tick_fraction)


def test_the_highest_rate_is_the_one_below_the_first_that_fails() -> None:
    points = [
        point(250.0),
        point(500.0, p99=1.4),
        point(1000.0),  # held by luck above a rate that did not
        point(250.0, case='floor'),
        point(500.0, case='floor'),
        point(250.0, case='processes', late=0.02),
    ]
    assert highest_held(points, 'single') == 250.0
    assert highest_held(points, 'floor') == 500.0
    assert highest_held(points, 'processes') is None
    assert highest_held(points, 'per_axis') is None  # not run
    failed = first_failed(points, 'single')
    assert failed is not None and failed.rate_hz == 500.0
    assert first_failed(points, 'floor') is None


def test_json_figures_carry_the_worst_axis_and_the_verdict() -> None:
    f = point(rate=1000.0, run=3.0, overruns=12).figures()
    assert f['case'] == 'single' and f['rate_hz'] == 1000.0
    assert f['drive']['y']['longest_late_run'] == 3.0
    assert f['longest_late_run'] == 3.0 and f['late_tick_fraction'] == 0.012
    assert f['failed'] == ['in a row', 'late ticks'] and f['holds'] is False
