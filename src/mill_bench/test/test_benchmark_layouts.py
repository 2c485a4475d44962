"""benchmark --layout/--layouts: which layouts run, bad values refused before anything runs."""

from __future__ import annotations

import argparse

import pytest
from mill_bench.benchmark import layouts_of, main
from mill_bringup.scenario import ScenarioError, load


def _args(**kwargs: object) -> argparse.Namespace:
    values = {'layout': None, 'layouts': None, 'record': False, **kwargs}
    return argparse.Namespace(**values)


def test_default_is_the_scenarios_layout() -> None:
    scen = load('slotting')
    assert layouts_of(_args(), scen) == ['processes']
    scen.layout = 'single'
    assert layouts_of(_args(), scen) == ['single']
    assert layouts_of(_args(layout='per_axis'), scen) == ['per_axis']


def test_several_layouts_in_the_order_given() -> None:
    got = layouts_of(_args(layouts='single, processes,per_axis'), load('slotting'))
    assert got == ['single', 'processes', 'per_axis']


@pytest.mark.parametrize(
    ('kwargs', 'message'),
    [
        ({'layouts': 'single,threads'}, "got 'threads'"),
        ({'layouts': 'single,single'}, 'names a layout twice'),
        ({'layouts': 'single,per_axis', 'record': True}, '--record measures one layout'),
    ],
)
def test_bad_layouts_are_refused(kwargs: dict[str, object], message: str) -> None:
    with pytest.raises(ScenarioError, match=message):
        layouts_of(_args(**kwargs), load('slotting'))


def test_main_refuses_a_bad_layout_in_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    # No ping-pong and no run: the layout is checked first.
    assert main(['slotting', '--layouts', 'processes,pairs']) == 1
    err = capsys.readouterr().err
    assert (
        err == "benchmark: error: layout must be one of processes, per_axis, single, got 'pairs'\n"
    )


def test_repeated_layouts_run_in_turn() -> None:
    from mill_bench.benchmark import schedule

    assert schedule(['single', 'processes'], 3) == [
        (0, 'single'),
        (0, 'processes'),
        (1, 'single'),
        (1, 'processes'),
        (2, 'single'),
        (2, 'processes'),
    ]
    assert schedule(['per_axis'], 1) == [(0, 'per_axis')]


@pytest.mark.parametrize(
    ('rates', 'median'),
    [([300.0], 300.0), ([500.0, 200.0, 400.0], 400.0), ([500.0, 200.0, 400.0, 100.0], 200.0)],
)
def test_the_median_run_stands_for_its_layout(rates: list[float], median: float) -> None:
    from types import SimpleNamespace

    from mill_bench.results import median_run

    runs = [SimpleNamespace(steps_per_second=r) for r in rates]
    assert median_run(runs).steps_per_second == median  # type: ignore[arg-type]


def test_repeat_below_one_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(['slotting', '--repeat', '0'])
    assert exc.value.code == 2
    assert '--repeat must be at least 1, got 0' in capsys.readouterr().err
