"""Parameter names in scenario files and overrides: a name no node declares is refused before
anything starts, as each node would refuse it at start-up; /** entries are for all nodes."""

from __future__ import annotations

from pathlib import Path

import pytest
from mill_bringup.jobs.registry import job_for

from mill_bringup import scenario

CONFIG = Path(__file__).resolve().parents[3] / 'config'
LAUNCH = """
mill_scenario:
  ros__parameters:
    launch:
      - plant mill_plant plant_node
      - trajectory mill_trajectory trajectory_node
      - x_observer mill_observers observer_node
      - x_controller mill_controllers axis_controller_node
      - y_controller mill_controllers axis_controller_node
"""


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / 'scen.yaml'
    path.write_text(text + LAUNCH)
    return path


@pytest.mark.parametrize('path', sorted(CONFIG.glob('*.yaml')), ids=lambda p: p.stem)
def test_every_shipped_scenario_names_only_declared_parameters(path: Path) -> None:
    scen = scenario.load(str(path))
    runs = [scen.variant(v) for v in scen.variants] or [scen]
    for run in runs:
        for node in run.nodes:
            run.parameters(node.name)


def test_an_override_of_an_unknown_name_is_refused(tmp_path: Path) -> None:
    scen = scenario.load(str(write(tmp_path, '')))
    with pytest.raises(scenario.ScenarioError) as caught:
        scen.add_override('x_controller.pd.omega=3.0')
    assert str(caught.value) == (
        "override 'x_controller.pd.omega=3.0': unknown parameter pd.omega=3.0 "
        '(did you mean pd.omega_c?): x_controller has no such parameter'
    )
    with pytest.raises(scenario.ScenarioError, match='none of x_controller, y_controller'):
        scen.add_override('*_controller.pd.omega=3.0')
    assert scen.overrides == {}


def test_a_glob_override_goes_to_the_nodes_that_declare_it(tmp_path: Path) -> None:
    scen = scenario.load(str(write(tmp_path, '')))
    scen.add_override('*.sample_period=0.002')
    # plant, trajectory, observer and controllers declare it
    assert set(scen.overrides) == {
        'plant',
        'trajectory',
        'x_observer',
        'x_controller',
        'y_controller',
    }
    scen.add_override('*.observer=dfo')  # only the observer has `observer`
    assert {n for n, o in scen.overrides.items() if 'observer' in o} == {'x_observer'}
    scen.add_override('*.use_sim_time=true')  # ROS's own parameter: every node has it
    assert all(o['use_sim_time'] is True for o in scen.overrides.values())


def test_a_shared_name_no_node_declares_is_refused_at_load(tmp_path: Path) -> None:
    path = write(
        tmp_path, '/**:\n  ros__parameters:\n    use_sim_time: true\n    sampel_period: 0.001\n'
    )
    with pytest.raises(scenario.ScenarioError) as caught:
        scenario.load(str(path))
    assert str(caught.value) == (
        f'{path}: /**: unknown parameter sampel_period=0.001 (did you mean sample_period?): '
        'no node of scenario scen declares it'
    )


def test_a_shared_name_some_node_declares_is_taken_by_those_nodes(tmp_path: Path) -> None:
    # `observer` is the observer's alone; the controllers and the plant do not get it.
    scen = scenario.load(str(write(tmp_path, '/**:\n  ros__parameters:\n    observer: dfo\n')))
    assert scen.parameters('x_observer')['observer'] == 'dfo'
    assert 'observer' not in scen.parameters('x_controller')


def test_a_node_entry_with_an_unknown_name_is_refused(tmp_path: Path) -> None:
    path = write(tmp_path, 'x_controller:\n  ros__parameters:\n    pd:\n      omegac: 3.0\n')
    scen = scenario.load(str(path))
    with pytest.raises(scenario.ScenarioError) as caught:
        job_for(scen)
    assert str(caught.value) == (
        f'{path}: entry x_controller: unknown parameter pd.omegac=3.0 '
        '(did you mean pd.omega_c?): x_controller has no such parameter'
    )


def test_an_entry_for_no_node_is_refused(tmp_path: Path) -> None:
    path = write(tmp_path, 'x_controler:\n  ros__parameters:\n    controller: pd\n')
    with pytest.raises(scenario.ScenarioError, match="entry 'x_controler' is for no node"):
        scenario.load(str(path))


def test_nested_parameters_read_as_dotted_names(tmp_path: Path) -> None:
    path = write(tmp_path, 'x_controller:\n  ros__parameters:\n    pd:\n      omega_c: 20\n')
    values = scenario.load(str(path)).parameters('x_controller')
    assert values['pd.omega_c'] == 20.0 and isinstance(values['pd.omega_c'], float)
