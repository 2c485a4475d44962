"""Scenario files under a machine namespace: every node gets its values in any namespace,
the namespace comes from the file or the command line, bad names are refused in one line."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from mill_bringup.runner.cli import main as run_scenario_main
from mill_bringup.scenario import ScenarioError

from mill_bringup import scenario

CONFIG = Path(__file__).resolve().parents[3] / 'config'


@pytest.mark.parametrize('path', sorted(CONFIG.glob('*.yaml')), ids=lambda p: p.stem)
def test_config_entries_apply_in_any_namespace(path: Path) -> None:
    # rcl reads a plain `plant:` entry only for /plant: under -r __ns:=/machine2 the node
    # would run on its defaults. Every node of our files is keyed /**/NAME.
    scen = scenario.load(str(path))
    raw = yaml.safe_load(path.read_text())
    for node in scen.nodes:
        assert f'/**/{node.name}' in raw, node.name
        assert node.name not in raw and f'/{node.name}' not in raw, node.name


def _write(tmp_path: Path, extra: str, key: str = 'plant') -> Path:
    path = tmp_path / 'scen.yaml'
    path.write_text(
        'mill_scenario:\n  ros__parameters:\n'
        '    launch: ["plant mill_plant plant_node"]\n'
        f'{extra}'
        f'{key}:\n  ros__parameters:\n    substeps: 8\n'
    )
    return path


@pytest.mark.parametrize('key', ['plant', '/plant', '/**/plant'])
def test_node_parameters_apply_everywhere_whatever_the_key(tmp_path: Path, key: str) -> None:
    scen = scenario.load(str(_write(tmp_path, '', key)))
    scen.add_override('plant.axes=["x", "y"]')
    assert scen.node_parameters() == {
        '/**/plant': {'ros__parameters': {'substeps': 8, 'axes': ['x', 'y']}}
    }
    assert scen.namespace == '/' and scen.remappings() == []


def test_namespace_from_the_file_and_the_private_clock(tmp_path: Path) -> None:
    scen = scenario.load(
        str(_write(tmp_path, '    namespace: machine2\n    private_clock: true\n'))
    )
    assert scen.namespace == '/machine2'
    assert scen.remappings() == ['__ns:=/machine2', '/clock:=/machine2/clock']
    scen.private_clock = False
    assert scen.remappings() == ['__ns:=/machine2']


def test_bad_namespace_in_a_file_is_one_line(tmp_path: Path) -> None:
    with pytest.raises(ScenarioError, match=r"scen.yaml: namespace '2x' is not valid"):
        scenario.load(str(_write(tmp_path, '    namespace: "2x"\n')))


NO_LAUNCH = 'no mill_scenario: ros__parameters: launch: list'


@pytest.mark.parametrize(
    ('text', 'message'),
    [
        ('', 'empty, not a scenario'),
        ('# to do\n', 'empty, not a scenario'),
        ('- plant\n', NO_LAUNCH),
        ('mill_scenario: 5\n', NO_LAUNCH),
        ('mill_scenario:\n  ros__parameters:\n    launch: 5\n', NO_LAUNCH),
    ],
)
def test_a_file_that_is_no_scenario_ends_run_scenario_in_one_line(
    capsys, tmp_path: Path, text: str, message: str
) -> None:
    path = tmp_path / 'scen.yaml'
    path.write_text(text)
    assert run_scenario_main([str(path), '--output', str(tmp_path / 'run')]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f'run_scenario: error: {path}: {message}']
    assert not (tmp_path / 'run').exists()  # nothing was started


@pytest.mark.parametrize(
    ('args', 'message'),
    [
        (['--namespace', 'ma-chine'], "namespace 'ma-chine' is not valid"),
        (['--private-clock'], 'a private clock needs a namespace'),
    ],
)
def test_bad_namespace_options_end_in_one_line(capsys, args: list[str], message: str) -> None:
    assert run_scenario_main(['slotting', *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith('run_scenario: error: ') and message in err[0]


@pytest.mark.parametrize('path', sorted(CONFIG.glob('*.yaml')), ids=lambda p: p.stem)
def test_rcl_reads_the_written_parameters_as_the_scenario_holds_them(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, path: Path
) -> None:
    # What the runner hands every node (RUN_DIR/parameters.yaml), read by rcl itself under a
    # namespace; a string such as "y" must stay a string (rcl reads a bare y as a bool).
    import rclpy
    from mill_common.env import ros_environment
    from rclpy.node import Node

    for key, value in ros_environment({}).items():
        monkeypatch.setenv(key, value)
    scen = scenario.load(str(path))
    for node in scen.nodes:
        if node.package in ('mill_controllers', 'mill_observers') and 'force' not in node.name:
            scen.add_override(f'{node.name}.axis="y"')  # also what a --param override writes
    params = tmp_path / 'parameters.yaml'
    params.write_text(scenario.dump_parameters(scen.node_parameters()))
    context = rclpy.Context()
    rclpy.init(args=['--ros-args', '--params-file', str(params)], context=context)
    try:
        for launch in scen.nodes:
            node = Node(
                launch.name,
                namespace='machine2',
                context=context,
                automatically_declare_parameters_from_overrides=True,
            )
            try:
                got = {
                    name: list(value.value) if hasattr(value.value, 'tolist') else value.value
                    for name, value in node._parameters.items()
                    if name not in ('use_sim_time', 'start_type_description_service')
                }
                want = scen.raw_parameters(launch.name)
                want.pop('use_sim_time', None)
                assert got == want, launch.name  # exact: floats are written as repr
            finally:
                node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
