"""benchmark --realtime: the rates it parses and which rate a layout holds."""

from __future__ import annotations

import pytest
from mill_bench.realtime_sweep import RatePoint, format_sweep, highest_held, parse_rates


def point(layout: str, rate: float, late: float, overruns: int = 0) -> RatePoint:
    return RatePoint(layout, rate, late, 1.0, 2.0, overruns, 1.5, ticks=int(3 * rate))


def test_rates_are_sorted_and_checked() -> None:
    assert parse_rates('1000,100,250,100') == [100.0, 250.0, 1000.0]
    with pytest.raises(ValueError, match="'fast' is not a rate"):
        parse_rates('100,fast')
    with pytest.raises(ValueError, match='outside'):
        parse_rates('0.5')
    with pytest.raises(ValueError, match='outside'):
        parse_rates('nan')


def test_a_rate_holds_below_one_percent_of_late_periods_on_the_worst_axis() -> None:
    points = [
        point('single', 100, 0.0),
        point('single', 500, 0.0099),
        point('single', 1000, 0.2),
        point('processes', 100, 0.0196),
    ]
    assert highest_held(points, 'single') == 500
    assert highest_held(points, 'processes') is None
    text = '\n'.join(format_sweep(points, ['processes', 'single']))
    assert 'layout processes: none of the rates tried' in text
    assert 'late ticks, layout single: 500 Hz' in text
    assert '1.96 %' in text


def test_a_rate_whose_ticks_come_late_does_not_hold_though_every_command_is_fresh() -> None:
    # one process: the drive's timer waits for the loop, so no period lacks a command
    points = [
        point('single', 250, 0.0, overruns=7),  # 7 of 750 ticks: 0.93 %
        point('single', 500, 0.0, overruns=15),  # 15 of 1500: exactly 1 %
        point('single', 1000, 0.0, overruns=476),
    ]
    assert [p.holds for p in points] == [True, False, False]
    assert highest_held(points, 'single') == 250
    text = '\n'.join(format_sweep(points, ['single']))
    assert '476 (15.87 %)' in text
