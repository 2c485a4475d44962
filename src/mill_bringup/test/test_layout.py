"""Process layouts (ROS-free): which nodes share a process, bad values in one line."""

from __future__ import annotations

from pathlib import Path

import pytest
from mill_bringup.layout import CONTAINER, processes
from mill_bringup.scenario import LAYOUTS, ScenarioError, check_layout, load

ROOT = Path(__file__).resolve().parents[3]


def _groups(name: str, layout: str, **kwargs: object) -> dict[str, list[str]]:
    return {p.name: p.node_names for p in processes(load(name), layout, **kwargs)}


def test_processes_gives_every_node_its_own() -> None:
    scen = load('slotting')
    groups = _groups('slotting', 'processes')
    assert groups == {n.name: [n.name] for n in scen.nodes}


def test_per_axis_puts_observer_and_controller_of_an_axis_together() -> None:
    assert _groups('slotting', 'per_axis') == {
        'plant': ['plant'],
        'trajectory': ['trajectory'],
        'x_axis': ['x_observer', 'x_controller'],
        'y_axis': ['y_observer', 'y_controller'],
        'z_axis': ['z_observer', 'z_controller'],
    }


def test_per_axis_groups_by_the_axis_parameter_not_the_name(tmp_path: Path) -> None:
    text = (ROOT / 'config' / 'chavez_conde.yaml').read_text()
    renamed = text.replace('x_observer', 'estimator').replace('x_controller', 'law')
    path = tmp_path / 'renamed.yaml'
    path.write_text(renamed)
    assert _groups(str(path), 'per_axis')['x_axis'] == ['estimator', 'law']


def test_single_puts_every_node_in_one_process() -> None:
    scen = load('slotting_adaptive_feed')
    (process,) = processes(scen, 'single')
    assert process.name == CONTAINER and process.container
    assert process.node_names == [n.name for n in scen.nodes]


def test_external_and_alone_nodes_stay_out_of_containers() -> None:
    groups = _groups('rubio', 'single', external=['trajectory'], alone=['force_process'])
    assert groups == {'force_process': ['force_process'], 'force_controller': ['force_controller']}
    # A group of one is no container: it is that node's process, named after it.
    assert not any(
        p.container
        for p in processes(load('rubio'), 'single', alone=['trajectory', 'force_process'])
    )


@pytest.mark.parametrize('name', sorted(p.stem for p in (ROOT / 'config').glob('*.yaml')))
@pytest.mark.parametrize('layout', LAYOUTS)
def test_every_node_runs_exactly_once(name: str, layout: str) -> None:
    scen = load(name)
    placed = [n for p in processes(scen, layout) for n in p.node_names]
    assert sorted(placed) == sorted(n.name for n in scen.nodes)


def test_bad_layout_is_refused_in_one_line(tmp_path: Path) -> None:
    with pytest.raises(
        ScenarioError, match="layout must be one of processes, per_axis, single, got 'pairs'"
    ):
        check_layout('pairs')
    text = (ROOT / 'config' / 'slotting.yaml').read_text()
    marker = '    # name package executable\n'
    path = tmp_path / 'bad.yaml'
    path.write_text(text.replace(marker, '    layout: threads\n' + marker))
    with pytest.raises(
        ScenarioError, match=r"bad\.yaml: layout must be one of .*got 'threads'"
    ) as caught:
        load(str(path))
    assert '\n' not in str(caught.value)


def test_scenario_file_chooses_the_layout(tmp_path: Path) -> None:
    text = (ROOT / 'config' / 'slotting.yaml').read_text()
    marker = '    # name package executable\n'
    path = tmp_path / 'packed.yaml'
    path.write_text(text.replace(marker, '    layout: per_axis\n' + marker))
    assert load(str(path)).layout == 'per_axis'
    assert load('slotting').layout == 'processes'
