"""benchmark: the eight-process layout's share of the empty-callback floor, run by run."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

from mill_bench.results import floor_lines


def run(steps_per_second: float) -> Any:
    return SimpleNamespace(steps_per_second=steps_per_second)


def test_each_run_is_compared_with_the_floor_measured_before_it() -> None:
    # The machine slowed down by half between the pairs: each pair still gives 60 / 75 %,
    # where medians of all floors against all runs would not.
    floors = [(1000.0, 800.0), (500.0, 400.0), (1000.0, 800.0)]
    lines = floor_lines(floors, [run(600.0), run(300.0), run(600.0)])
    assert lines[1].split() == ['1000', '[500-1000]', 'steps/s']
    assert lines[2].split()[:3] == ['800', '[400-800]', 'steps/s']
    assert 'at 60 [60-60] % of the floor, 75 [75-75] % of the floor with the listener' in lines[3]


def test_without_runs_only_the_floor_is_given() -> None:
    lines = floor_lines([(900.0, 700.0)], [])
    assert len(lines) == 3 and lines[1].split() == ['900', 'steps/s']
