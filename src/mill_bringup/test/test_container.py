"""The container's choice of nodes (ROS-free): names from the scenario, one-line refusals."""

from __future__ import annotations

from pathlib import Path

import pytest
from mill_bringup.catalogue import KINDS, kind_of
from mill_bringup.container import (
    USAGE,
    ContainerError,
    main,
    makers,
    scenario_launch,
)

ROOT = Path(__file__).resolve().parents[3]
SLOTTING = str(ROOT / 'config' / 'slotting.yaml')
RUBIO = str(ROOT / 'config' / 'rubio.yaml')


def test_every_executable_of_every_scenario_has_a_factory() -> None:
    for path in sorted((ROOT / 'config').glob('*.yaml')):
        for package, executable in scenario_launch([str(path)]).values():
            kind = kind_of(package, executable)
            assert callable(kind.build()), kind.factory


def test_factories_take_node_options() -> None:
    # Every factory passes rclpy Node options on (the container's cli_args).
    import inspect

    for kind in KINDS:
        params = inspect.signature(kind.build()).parameters.values()
        assert any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params), kind.factory


def test_only_the_drive_is_a_lifecycle_node() -> None:
    managed = [(k.package, k.executable) for k in KINDS if k.lifecycle]
    assert managed == [('mill_plant', 'plant_node')]


def test_makers_keep_the_scenario_names_in_the_given_order() -> None:
    built = makers(['x_controller', 'x_observer'], [SLOTTING])
    assert [name for name, _make in built] == ['x_controller', 'x_observer']


def test_scenario_is_found_among_several_files(tmp_path: Path) -> None:
    other = tmp_path / 'gains.yaml'
    other.write_text('/**/x_controller:\n  ros__parameters:\n    controller: pd\n')
    assert scenario_launch([str(other), RUBIO])['force_process'] == (
        'mill_plant',
        'force_process_node',
    )


@pytest.mark.parametrize(
    ('names', 'files', 'message'),
    [
        (['spindle'], [SLOTTING], "the scenario has no node 'spindle'"),
        ([], [SLOTTING], 'no node named'),
        (['plant', 'plant'], [SLOTTING], 'node plant named twice'),
        (['plant'], [], 'no --params-file has a mill_scenario'),
    ],
)
def test_bad_choices_are_refused_in_one_line(
    names: list[str], files: list[str], message: str
) -> None:
    with pytest.raises(ContainerError, match=message) as caught:
        makers(names, files)
    assert '\n' not in str(caught.value)


def test_unknown_executable_is_refused(tmp_path: Path) -> None:
    scen = tmp_path / 'scen.yaml'
    scen.write_text(
        'mill_scenario:\n  ros__parameters:\n    launch: ["spindle mill_plant spindle_node"]\n'
    )
    with pytest.raises(ContainerError, match=r'no node kind mill_plant spindle_node \(known: '):
        makers(['spindle'], [str(scen)])


def test_main_help_and_bad_node(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(['mill_container', '--help']) == 0
    assert capsys.readouterr().out.strip() == USAGE.strip()
    assert main(['mill_container', 'spindle', '--ros-args', '--params-file', SLOTTING]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mill_container: error: the scenario has no node 'spindle'")
    assert err.count('\n') == 1


def test_a_params_file_with_aliases_is_refused_in_one_line(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    path = tmp_path / 'bomb.yaml'
    path.write_text('a: &a [1, 2]\nb: [*a, *a]\n')
    assert main(['mill_container', 'plant', '--ros-args', '--params-file', str(path)]) == 2
    err = capsys.readouterr().err
    assert err == (
        f'mill_container: error: --params-file {path}: an anchor (&a) at line 1, column 4: '
        'anchors are refused\n'
    )
