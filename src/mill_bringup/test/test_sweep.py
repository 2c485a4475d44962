"""offline_sim --sweep: the grid, its table, one-line errors, and the same figures as a
single offline run of each point."""

from __future__ import annotations

import argparse

import pytest
from mill_bringup.cli import add_scenario_arguments
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.registry import job_for
from mill_bringup.offline import main
from mill_bringup.sweep import (
    SweepAxis,
    figures,
    grid,
    parse_sweep,
    run_grid,
    split_values,
    table,
)

from mill_bringup import scenario


def test_values_split_on_commas_outside_brackets_and_quotes() -> None:
    assert split_values('8, 12,16') == ['8', '12', '16']
    assert split_values('[1, 2],[3, 4]') == ['[1, 2]', '[3, 4]']
    assert split_values('"a,b",c') == ['"a,b"', 'c']


@pytest.mark.parametrize(
    ('text', 'why'),
    [
        ('omega_c=1,2', 'NODE.NAME'),
        ('x.omega_c', 'NODE.NAME'),
        ('.omega_c=1', 'NODE.NAME'),
        ('x.omega_c=1,,2', 'empty value'),
        ('x.omega_c=1,1', 'twice'),
    ],
)
def test_a_malformed_sweep_is_refused_in_one_line(text: str, why: str) -> None:
    with pytest.raises(scenario.ScenarioError, match=why):
        parse_sweep(text)


def test_the_grid_is_every_combination_the_last_axis_fastest() -> None:
    axes = [parse_sweep('a.p=1,2'), parse_sweep('*_b.q=x,y,z')]
    assert axes[1] == SweepAxis('*_b.q', ('x', 'y', 'z'))
    points = grid(axes)
    assert len(points) == 6
    assert points[0] == ('a.p=1', '*_b.q=x')
    assert points[1] == ('a.p=1', '*_b.q=y')
    assert points[5] == ('a.p=2', '*_b.q=z')
    with pytest.raises(scenario.ScenarioError, match='twice'):
        grid([axes[0], axes[0]])


def _args(*extra: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_scenario_arguments(parser)
    return parser.parse_args(['slotting', '--duration', '0.2', '--skip', '0.05', *extra])


def test_each_point_gives_the_figures_of_its_own_offline_run() -> None:
    args = _args()
    axes = [parse_sweep('*_controller.pd.omega_c=8,30'), parse_sweep('x_observer.gpi.omega_o=9')]
    results = run_grid(args, grid(axes), jobs=2)
    assert [r.index for r in results] == [0, 1]
    assert [r.error for r in results] == ['', '']
    for r in results:
        scen = scenario.load('slotting')
        for text in ('trajectory.duration=0.2', *r.overrides):
            scen.add_override(text)
        job = job_for(scen)
        assert r.figures[''] == figures(job.summary(simulate(job), 0.05))
    # the grid's values reached the runs: the two gains track differently
    assert results[0].figures['']['y RMS e'] != results[1].figures['']['y RMS e']


def test_a_point_a_parameter_refuses_is_one_line_and_the_others_run() -> None:
    args = _args()
    axes = [parse_sweep('*_controller.pd.omega_c=12,fast')]
    results = run_grid(args, grid(axes), jobs=1)
    assert results[0].error == '' and results[0].figures['']['x RMS e'] > 0.0
    assert 'pd.omega_c' in results[1].error and '\n' not in results[1].error
    text = table(axes, results)
    lines = text.splitlines()
    assert len(lines) == 3
    assert lines[0].split()[:2] == ['*_controller.pd.omega_c', 'x']
    assert lines[2].split()[:2] == ['fast', 'error:']


def test_offline_sim_sweep_prints_the_table_and_exits_1_on_a_failed_point(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code = main(
        ['slotting', '--duration', '0.1', '--jobs', '1', '--sweep', 'z_controller.pd.omega_c=12,-1']
    )
    out, err = capsys.readouterr()
    assert code == 1
    assert '[2/2] z_controller.pd.omega_c=-1: error: ' in err
    rows = out.strip().splitlines()[-2:]
    assert rows[0].split()[0] == '12' and rows[1].split()[:2] == ['-1', 'error:']
    assert main(['slotting', '--sweep', 'omega_c=1']) == 2
