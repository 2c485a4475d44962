"""After `colcon build`, executables sit where `ros2 run <package> <executable>` looks."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

# One worker runs the module, so that the install space is built once (pytest-xdist).
pytestmark = pytest.mark.xdist_group('colcon_build')

REPO = Path(__file__).resolve().parents[1]
PACKAGES = sorted(p.parent.name for p in (REPO / 'src').glob('*/package.xml'))


def console_scripts(package: str) -> list[str]:
    text = (REPO / 'src' / package / 'setup.py').read_text()
    return re.findall(r"'([a-z_]+) = [a-z_.]+:main'", text)


@pytest.fixture(scope='module')
def install_space(tmp_path_factory) -> Path:
    colcon = Path(sys.executable).parent / 'colcon'
    work = tmp_path_factory.mktemp('colcon')
    proc = subprocess.run(
        [
            str(colcon),
            '--log-base',
            str(work / 'log'),
            'build',
            '--base-paths',
            str(REPO / 'src'),
            '--build-base',
            str(work / 'build'),
            '--install-base',
            str(work / 'install'),
        ],
        cwd=work,
        capture_output=True,
        text=True,
        timeout=600,
        env={**os.environ, 'PYTHONDONTWRITEBYTECODE': '1'},
    )
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    return work / 'install'


def test_every_package_builds_and_installs_its_executables(install_space):
    assert set(PACKAGES) == {
        'mill_common',
        'mill_models',
        'mill_bag',
        'mill_plant',
        'mill_trajectory',
        'mill_controllers',
        'mill_observers',
        'mill_analysis',
        'mill_bringup',
        'mill_bench',
    }
    for package in PACKAGES:
        prefix = install_space / package
        assert (prefix / 'share/ament_index/resource_index/packages' / package).is_file()
        assert (prefix / 'share' / package / 'package.xml').is_file()
        for exe in console_scripts(package):
            path = prefix / 'lib' / package / exe
            assert path.is_file() and os.access(path, os.X_OK), path


def test_installed_executable_runs(install_space):
    exe = install_space / 'mill_plant/lib/mill_plant/plant_node'
    proc = subprocess.run([str(exe), '--help'], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0
    assert 'lockstep_timeout' in proc.stdout


def test_scenarios_are_installed_with_bringup(install_space):
    share = install_space / 'mill_bringup/share/mill_bringup'
    assert (share / 'config/slotting.yaml').is_file()
