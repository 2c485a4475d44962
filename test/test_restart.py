"""A node killed mid-job is started again and rejoins: the plant offers the step again.

run_scenario --respawn starts a dead node again (as ros2 launch's respawn does); the plant
offers an unanswered step every second, so the new process gets the state (and /clock, which
the trajectory answers with the reference again) of the step the graph waits on.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess

import pytest

from test.conftest import EXTENDED, start_scenario


def run_and_kill(ros_env, tmp_path, victim: str) -> tuple[int, str, dict]:
    """Run 3 s of the slotting job; SIGKILL `victim` once the job has stepped.

    The trigger is the first progress line (printed at the first step after 0): the next
    comes 5 s later, and a 3 s run may be over by then (about 500 steps/s here).
    """
    out = tmp_path / 'run'
    proc = start_scenario(
        ros_env,
        *('slotting', '--duration', '3', '--compare-offline', '--respawn', '--output', str(out)),
    )
    killed = False
    lines = []
    assert proc.stderr is not None
    for line in proc.stderr:  # progress lines 't / 3.00 s' every 5 s (not a terminal)
        lines.append(line)
        if not killed and re.match(r'\s*[0-9.]+ / 3\.00 s', line):
            pid = subprocess.run(  # a child of this runner only: other runs may share the host
                ['pgrep', '-P', str(proc.pid), '-f', f'__node:={victim} '],
                capture_output=True,
                text=True,
            ).stdout.split()
            assert pid, f'no process of {victim}'
            os.kill(int(pid[0]), signal.SIGKILL)
            killed = True
    stdout = proc.stdout.read() if proc.stdout else ''
    code = proc.wait(timeout=600)
    assert killed, 'the run ended before the kill: ' + ''.join(lines[-5:])
    assert (out / 'summary.json').exists(), f'no summary (exit {code}):\n' + ''.join(lines[-30:])
    summary = json.loads((out / 'summary.json').read_text())
    return code, stdout + ''.join(lines), summary


@pytest.mark.system
def test_killed_adrc_controller_rejoins_and_the_record_equals_offline(ros_env, tmp_path) -> None:
    # adrc holds no state: the restarted law computes what the old one would have.
    code, text, summary = run_and_kill(ros_env, tmp_path, 'x_controller')
    assert code == 0, text[-3000:]
    assert any('x_controller exited with code -9' in p for p in summary['problems'])
    assert summary['missing_samples'] == {}
    # The command it was sending when it died may have reached the plant and not the runner.
    assert summary['lost_with_restarts'] in ({}, {'mill/x/joint_command': 1})
    assert summary['offline_max_difference'] == 0.0


@pytest.mark.system
@EXTENDED  # a killed node rejoining: the controller's test makes that claim in CI
def test_killed_observer_rejoins_and_the_job_finishes_within_the_limit(ros_env, tmp_path) -> None:
    # The new observer starts from the measurement (velocity and disturbance 0): its
    # estimate differs from the old one's, the run from the offline one, by a transient.
    code, text, summary = run_and_kill(ros_env, tmp_path, 'y_observer')
    assert code == 0, text[-3000:]
    assert any('y_observer exited with code -9' in p for p in summary['problems'])
    assert summary['events'] == []  # no following-error trip (1 mm in the scenario)
    assert summary['missing_samples'] == {}
    assert summary['lost_with_restarts'] in ({}, {'mill/y/estimate': 1})
    assert 0.0 < summary['offline_max_difference'] < 1e-3
