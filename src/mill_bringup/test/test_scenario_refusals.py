"""Issue 37, points 5 and 6: what made run_scenario print a traceback, or a 140 MB line from
a 478-byte parameter file, ends it in one line before anything starts (exit code 2, as every
refusal of a scenario: docs/reliability.md)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from mill_bringup.runner.cli import main as run_scenario_main

OVERFLOW = "OverflowError: (34, 'Numerical result out of range')"
BOMB = 'a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]\n' + ''.join(
    f'{n}: &{n} [{", ".join([f"*{p}"] * 9)}]\n' for p, n in zip('abcdefgh', 'bcdefghi', strict=True)
)
# The wrapper's one child is run_scenario: its peak resident memory, printed on stdout.
PEAK = (
    'import resource, subprocess, sys\n'
    'done = subprocess.run(sys.argv[1:])\n'
    'print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)\n'
    'sys.exit(done.returncode)\n'
)


@pytest.mark.parametrize(
    ('args', 'line'),
    [
        (
            ['--duration', '1e300'],
            'trajectory: invalid parameter duration=1e+300: must be in [0.0, 86400.0]',
        ),
        (['--duration', 'inf'], '--duration must be a finite number > 0, got inf'),
        (
            ['-p', 'trajectory.linear.feed_rate=1e-12'],
            'trajectory: the job would end at t = 1.6e+11 s, after 86400 s (a day): give a '
            'duration or a faster path',
        ),
        (
            ['-p', 'x_controller.gpi.omega_n=1e300'],
            'x_controller: controller adrc cannot run with its values: gpi (not the running '
            f'law): {OVERFLOW}',
        ),
        (
            ['-p', 'x_controller.gpi.omega_n=1e300', '--controller', 'gpi'],
            f'x_controller: controller gpi cannot run with its values: {OVERFLOW}',
        ),
        (
            ['-p', 'plant.substeps=1000000000'],
            'plant: invalid parameter substeps=1000000000: must be a whole number in [1, 1000]',
        ),
        (
            ['-p', 'x_observer.use_sim_time=maybe'],
            "x_observer: invalid parameter use_sim_time='maybe': must be true or false",
        ),
        (
            ['rubio', '-p', 'force_controller.force_control.natural_frequency=1e300'],
            f'force_controller: force_controller fixed cannot run with its values: {OVERFLOW}',
        ),
    ],
    ids=[
        'duration',
        'duration-inf',
        'path-too-long',
        'gain',
        'gain-running',
        'substeps',
        'sim',
        'force-gain',
    ],
)
def test_a_value_nothing_can_run_with_ends_run_scenario_in_one_line(
    capsys, tmp_path: Path, args: list[str], line: str
) -> None:
    scenario = [] if args[0] == 'rubio' else ['slotting']
    assert run_scenario_main([*scenario, *args, '--output', str(tmp_path / 'run')]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f'run_scenario: error: {line}']
    assert not (tmp_path / 'run').exists()  # nothing was started


def test_the_alias_bomb_is_one_short_line_in_little_memory(tmp_path: Path) -> None:
    path = tmp_path / 'bomb.yaml'
    path.write_text(BOMB)
    assert len(BOMB) < 478
    runner = [sys.executable, '-m', 'mill_bringup.runner']  # run_scenario, whatever PATH holds
    command = [sys.executable, '-c', PEAK, *runner, '--params-file', str(path)]
    done = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert done.stderr.splitlines() == [
        f'run_scenario: error: params_file {path}: an anchor (&a) at line 1, column 4: '
        'anchors are refused'
    ]
    peak_mb = int(done.stdout.split()[-1]) / 1024  # ru_maxrss is in kB on Linux
    assert peak_mb < 250, peak_mb  # 632 MB before (and 78 MB measured after)
