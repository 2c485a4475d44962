"""Between jobs, with a drive that stays up (`--external plant`), and a driver that dies.

- The drive (`mill_plant.plant_node`, timing realtime, 250 Hz) runs on its own. A probe
  commands x for a few periods as a controller would (effort 0) and then falls silent: the
  drive stops x and latches it (its motion guard, or the window at rest: 0.5 s), as at the
  end of a job whose controllers were stopped before the drive. The next job refuses to
  start on it: exit code 2, one line naming the axis and the stop's reason, summary.json
  with outcome `refused`, and nothing of the job started (the drive saw no command). With
  `--rearm` the runner calls the drive's ~/release first (the drive logs it), and the job
  runs on a released axis: the drive never says "commands arriving, but stopped" (the second
  job of issue 32 ran on braked axes). After the release with no job yet running, x is not
  stopped again.
- The contract's driver (test_realtime_driver) killed mid-job: the run ends with exit code 1
  and writes summary.json, its failure the drive gone silent.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

from test.conftest import run_scenario
from test.test_realtime_driver import DRIVER

# Timing under load is what it checks: alone on the machine (scripts/test.sh, serial).
pytestmark = pytest.mark.serial

PERIOD = 0.004  # [s]
# Table 1's machine (the plant's own), the tuning rule for 250 Hz and one sample of delay.
TOLD = [
    '*.design_period=0.0',
    '*_observer.observer=eso',
    '*_observer.eso.omega_o=0.0',
    '*_controller.pd.omega_c=0.0',
    f'*.sample_period={PERIOD!r}',
]

PROBE = """
import sys, time
import rclpy
from rclpy.node import Node
from sensor_msgs.msg import JointState

rclpy.init()
node = Node('x_controller')  # the owner the drive expects (its publisher GID is checked)
pub = node.create_publisher(JointState, 'mill/x/joint_command', 10)
answered = []

def on_state(msg):
    if len(answered) < 5:  # a controller's commands for five periods, then silence
        cmd = JointState(name=['x'], effort=[0.0])
        cmd.header.stamp = msg.header.stamp
        cmd.header.frame_id = 'x_controller'
        pub.publish(cmd)
        answered.append(msg.header.stamp)

node.create_subscription(JointState, 'mill/x/state', on_state, 10)
end = time.monotonic() + 60.0
while len(answered) < 5 and time.monotonic() < end:
    rclpy.spin_once(node, timeout_sec=0.1)
t = time.monotonic() + 1.0
while time.monotonic() < t:  # the commands delivered before the probe leaves
    rclpy.spin_once(node, timeout_sec=0.1)
print('answered', len(answered), flush=True)
"""


def stop_reason(log: str, axis: str) -> str:
    """The reason of the drive's first stop of the axis, as its status gives it
    (`<axis>.stopped`): its log line without what the log adds (the topic, the distance)."""
    found = re.search(rf'axis {axis}: stopped: (.*?); braked until re-armed', log)
    assert found is not None, log[-3000:]
    return found.group(1).split(f' on mill/{axis}/joint_command')[0]


def wait_for_line(path: Path, needle: str, proc: subprocess.Popen[str], after: int = 0) -> None:
    """Until the log at `path` holds `needle` after its first `after` characters."""
    deadline = time.monotonic() + 300.0
    while needle not in path.read_text()[after:]:
        assert proc.poll() is None, path.read_text()[-3000:]
        assert time.monotonic() < deadline, f'no "{needle}" in {path}'
        time.sleep(0.1)


def runner_args(out: Path, *more: str) -> list[str]:
    return [
        *('slotting', '--timing', 'realtime', '--external', 'plant', '--duration', '1'),
        *('--layout', 'single', '--output', str(out), '--quiet'),
        *(arg for text in TOLD for arg in ('-p', text)),
        *more,
    ]


@pytest.mark.system
def test_a_job_refuses_a_latched_axis_and_rearm_releases_it(ros_env, tmp_path: Path) -> None:
    log = tmp_path / 'plant.log'
    config = Path(__file__).parents[1] / 'config' / 'slotting.yaml'
    args = ['-m', 'mill_plant.plant_node', '--ros-args', '-r', '__node:=plant']
    args += ['--params-file', str(config)]
    args += ['-p', 'plant:timing:=realtime', '-p', f'plant:sample_period:={PERIOD!r}']
    script = tmp_path / 'probe.py'
    script.write_text(PROBE)
    with open(log, 'w') as plant_out:
        plant = subprocess.Popen(
            [sys.executable, *args], env=ros_env, stdout=plant_out, stderr=subprocess.STDOUT
        )
        try:
            wait_for_line(log, 'active: applying commands', plant)
            probe = subprocess.run(
                [sys.executable, str(script)],
                env=ros_env,
                capture_output=True,
                text=True,
                timeout=120,
            )
            assert probe.stdout.strip() == 'answered 5', probe.stdout + probe.stderr
            wait_for_line(log, 'axis x: stopped: ', plant)
            reason = stop_reason(log.read_text(), 'x')

            refused = run_scenario(ros_env, *runner_args(tmp_path / 'refused'))
            said = refused.stdout + refused.stderr
            assert refused.returncode == 2, said[-3000:]
            line = refused.stderr.strip().splitlines()[-1]
            assert line.startswith(
                f'run_scenario: error: axis x held stopped by the drive plant ({reason}): '
                'job not started; '
            ), said[-3000:]
            assert refused.stdout.startswith('REFUSED: x axis: refused (plant): '), said[-3000:]
            summary = json.loads((tmp_path / 'refused' / 'summary.json').read_text())
            assert (summary['outcome'], summary['exit_code']) == ('refused', 2)
            assert [f['kind'] for f in summary['failures']] == ['refused']
            assert 'commands arriving' not in log.read_text()  # no controller reached it

            before = len(log.read_text())
            rearmed = run_scenario(ros_env, *runner_args(tmp_path / 'rearmed', '--rearm'))
            said = rearmed.stdout + rearmed.stderr
            summary = json.loads((tmp_path / 'rearmed' / 'summary.json').read_text())
            assert summary['outcome'] != 'refused', said[-3000:]
            assert summary['rearmed'] == {'x': reason}, said[-3000:]
            assert "re-armed before the start (--rearm, the drive's ~/release): x" in said
            after = log.read_text()[before:]
            assert '~/release: released x' in after
            assert 'commands arriving, but stopped' not in after, after[-3000:]
            assert 'axis x: fresh commands: released' in after, after[-3000:]
            # between the release and the job's first command, x was not stopped again
            released_at = after.index('~/release: released x')
            armed_at = after.index('axis x: fresh commands: released')
            assert 'axis x: stopped' not in after[released_at:armed_at], after[-3000:]
        finally:
            plant.terminate()
            plant.wait(timeout=30)


# The contract's driver, killed (SIGKILL, by itself) once it has taken this many commands:
# about one second of the job at 250 Hz on three axes.
KILLED_AFTER = 750
DYING = DRIVER.replace(
    '        self.newest[axis] = msg.effort[0]\n',
    '        self.newest[axis] = msg.effort[0]\n'
    "        self.taken = getattr(self, 'taken', 0) + 1\n"
    f'        if self.taken == {KILLED_AFTER}:\n'
    '            os.kill(os.getpid(), 9)\n',
)


@pytest.mark.system
def test_a_run_whose_driver_was_killed_writes_its_summary(ros_env, tmp_path: Path) -> None:
    assert DYING != DRIVER
    script = tmp_path / 'dying_driver.py'
    script.write_text(DYING)
    driver = subprocess.Popen(
        [sys.executable, str(script), repr(PERIOD)],
        env=ros_env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    out = tmp_path / 'run'
    try:
        proc = run_scenario(
            ros_env,
            *('slotting', '--timing', 'realtime', '--external', 'plant', '--duration', '20'),
            *('--layout', 'single', '--output', str(out), '--quiet'),
            *(arg for text in TOLD for arg in ('-p', text)),
        )
    finally:
        driver.kill()
        driver_log = driver.communicate(timeout=30)[0]
    said = proc.stdout[-2000:] + proc.stderr[-3000:] + driver_log[-1000:]
    assert driver.returncode == -9, said
    assert proc.returncode == 1, said
    summary = json.loads((out / 'summary.json').read_text())
    assert (summary['outcome'], summary['exit_code']) == ('failed', 1)
    assert 'drive_silent' in [f['kind'] for f in summary['failures']], said
    assert summary['error'].startswith('the drive went silent: nothing on mill/'), said
    assert (
        proc.stderr.strip()
        .splitlines()[-1]
        .startswith('run_scenario: error: the drive went silent')
    ), said
