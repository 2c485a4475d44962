"""benchmark --layout/--layouts: which layouts run, bad values refused before anything runs."""

from __future__ import annotations

import argparse

import pytest
from mill_bringup.benchmark import layouts_of, main
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
