"""Every executable answers --help; every package is a well-formed ament_python package.

`--help` returns before rclpy is initialised, so these tests start no ROS node.
"""

from __future__ import annotations

import configparser
import re
import subprocess
import sys
import xml.etree.ElementTree as ET

import pytest
from mill_bringup.job_server import parameter_specs as job_server_specs
from mill_bringup.machine_view import parameter_specs as view_specs
from mill_controllers.config import parameter_specs as controller_specs
from mill_observers.config import parameter_specs as observer_specs
from mill_plant.config import parameter_specs as plant_specs
from mill_trajectory.config import parameter_specs as trajectory_specs

from test.conftest import REPO

PACKAGES = sorted(p.parent for p in (REPO / 'src').glob('*/package.xml'))

# module, executable name in the usage line, its specs, parameters that must be listed
NODES = [
    (
        'mill_plant.plant_node',
        'plant_node',
        plant_specs,
        ['mass', 'cutting_model', 'lockstep_timeout'],
    ),
    (
        'mill_controllers.axis_controller_node',
        'axis_controller_node',
        controller_specs,
        ['controller', 'pd.omega_c', 'axis'],
    ),
    ('mill_observers.observer_node', 'observer_node', observer_specs, ['gpi.omega_o', 'axis']),
    ('mill_trajectory.trajectory_node', 'trajectory_node', trajectory_specs, ['linear.feed_rate']),
    ('mill_bringup.machine_view', 'machine_view', view_specs, ['robot_description', 'trace_rate']),
    ('mill_bringup.job_server', 'job_server', job_server_specs, ['runs_dir', 'hold_timeout']),
]


def _help(module: str, env: dict[str, str]) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, '-m', module, '--help'],
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )


@pytest.mark.parametrize(
    ('module', 'executable', 'specs', 'required'), NODES, ids=[n[1] for n in NODES]
)
def test_node_help_lists_parameters(ros_env, module, executable, specs, required) -> None:
    done = _help(module, ros_env)
    assert done.returncode == 0, done.stderr
    out = done.stdout
    assert out.startswith(f'usage: {executable} '), out
    assert 'parameters:' in out
    # One line per parameter: the name, then its description.
    lines = {}
    for line in out.splitlines():
        match = re.match(r'^  (\S+)\s{2,}(\S.*)$', line)
        if match:
            lines[match.group(1)] = match.group(2)
    for name in required:
        assert name in lines, f'{name} missing from --help of {module}:\n{out}'
    for name, spec in specs():
        assert name in lines, f'{name} missing from --help of {module}'
        assert lines[name].startswith(spec.description), (name, lines[name])
        assert spec.description.strip(), f'{name} has no description'


@pytest.mark.parametrize(
    'module', ['mill_bringup.runner', 'mill_bringup.offline', 'mill_trajectory.preview']
)
def test_tool_help(ros_env, module) -> None:
    done = _help(module, ros_env)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith('usage: '), done.stdout


def test_all_packages_found() -> None:
    names = {p.name for p in PACKAGES}
    expected = {
        'mill_analysis',
        'mill_bag',
        'mill_bench',
        'mill_bringup',
        'mill_common',
        'mill_controllers',
        'mill_models',
        'mill_observers',
        'mill_plant',
        'mill_trajectory',
    }
    assert expected <= names


@pytest.mark.parametrize('package', PACKAGES, ids=[p.name for p in PACKAGES])
def test_package_xml(package) -> None:
    root = ET.parse(package / 'package.xml').getroot()
    assert root.tag == 'package'
    assert root.get('format') == '3'
    assert root.findtext('name') == package.name
    assert root.findtext('export/build_type') == 'ament_python'


@pytest.mark.parametrize('package', PACKAGES, ids=[p.name for p in PACKAGES])
def test_setup_cfg_installs_scripts_for_ros2_run(package) -> None:
    cfg = configparser.ConfigParser()
    assert cfg.read(package / 'setup.cfg'), f'{package.name} has no setup.cfg'
    expected = f'$base/lib/{package.name}'
    assert cfg.get('develop', 'script_dir', fallback=None) == expected
    assert cfg.get('install', 'install_scripts', fallback=None) == expected
