"""A G-code part distributed in lockstep equals the offline run (issue 24): the papers' slot
as G-code, and a part whose spindle is off for part of the cut (the cutting force too)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from test.conftest import run_scenario

CONFIG = Path(__file__).resolve().parents[1] / 'config'
# The slot's tool 5 mm deep in the work: 1 mm cut, 1 mm with the spindle off, 1 mm cut.
PART = 'G21 G90 G17\nS1800 M3\nG1 Y-104 F180\nM5\nG1 Y-103\nM3\nG1 Y-102\nM30\n'


def _run(env: dict[str, str], out: Path, *args: str) -> dict:
    proc = run_scenario(
        env, 'slotting', *args, '--compare-offline', '--quiet', '--output', str(out)
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads((out / 'summary.json').read_text())


@pytest.mark.system
def test_the_slot_as_gcode_runs_distributed_as_offline(ros_env, tmp_path) -> None:
    program = str(CONFIG / 'slotting.ngc')
    summary = _run(ros_env, tmp_path / 'run', '--program', program, '--duration', '3')
    assert summary['samples'] == 3001
    assert summary['missing_samples'] == {}
    assert summary['offline_max_difference'] == 0.0
    assert summary['problems'] == []


@pytest.mark.system
def test_the_spindle_switches_the_cutting_force_as_offline(ros_env, tmp_path) -> None:
    part = tmp_path / 'part.ngc'
    part.write_text(PART)
    summary = _run(ros_env, tmp_path / 'run', '--program', str(part), '--record')
    # the force of every sample, zero where the spindle is off (offline: test_spindle_program)
    assert set(summary['differences']) == {'tracking_error', 'cutting_force'}
    assert summary['offline_max_difference'] == 0.0
    assert summary['missing_samples'] == {}
