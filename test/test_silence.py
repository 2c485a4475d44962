"""Nobody hangs silently: a dead plant is named by everyone who waits for it, and the nodes
of a killed runner end with it.

The first test starts a one-axis lockstep graph by hand (the runner would stop the graph as
soon as the plant dies, before anyone could notice the silence), kills the plant mid-job and
reads what the controller, the observer and the trajectory say on /diagnostics and when they
end. The second kills a runner with SIGKILL and looks for its nodes.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from mill_common.ros import DATA_QOS, from_stamp
from rosgraph_msgs.msg import Clock

from mill_common import topics
from test.conftest import ros_node, wait_until

WARN_TIME = 0.5  # [s] input_warn_time of the watching nodes
TIMEOUT = 3.0  # [s] input_timeout of the watching nodes
WATCHERS = {  # node -> (module, executable, the input the plant fed it)
    'x_controller': (
        'mill_controllers.axis_controller_node',
        'axis_controller_node',
        topics.state('x'),
    ),
    'x_observer': ('mill_observers.observer_node', 'observer_node', topics.state('x')),
    'trajectory': ('mill_trajectory.trajectory_node', 'trajectory_node', topics.CLOCK),
}


def _silence(text: str, topic: str) -> list[float]:
    """The lengths of silence stated for `topic` from the plant, in 'nothing on ...' lines."""
    pattern = rf'nothing on {re.escape(topic)} for ([0-9.]+) s \(from plant\)'
    return [float(s) for s in re.findall(pattern, text)]


@pytest.mark.system
def test_a_dead_plant_is_named_and_its_peers_end_after_input_timeout(start_node) -> None:
    watch = ('-p', f'input_warn_time:={WARN_TIME}', '-p', f'input_timeout:={TIMEOUT}')
    nodes = {name: start_node(module, name, *watch) for name, (module, _, _) in WATCHERS.items()}
    plant = start_node(
        'mill_plant.plant_node',
        'plant',
        *('-p', 'plant:axes:=["x"]', '-p', 'plant:min_subscribers:=2'),
        *('-p', 'plant:cutting_model:=none'),
    )
    statuses: list[DiagnosticStatus] = []
    ticks: list[int] = []
    with ros_node('silence_listener') as (node, executor):
        node.create_subscription(
            DiagnosticArray, topics.DIAGNOSTICS, lambda m: statuses.extend(m.status), 100
        )
        node.create_subscription(
            Clock, topics.CLOCK, lambda m: ticks.append(from_stamp(m.clock)), DATA_QOS
        )

        def spin_until(predicate, timeout: float) -> bool:
            deadline = time.monotonic() + timeout
            while time.monotonic() < deadline and not predicate():
                executor.spin_once(timeout_sec=0.05)
            return predicate()

        def heard(name: str) -> bool:
            return any(s.name == f'{name}: inputs' for s in statuses)

        # The job runs (0.3 s of machine time) and this listener hears every watcher's
        # /diagnostics (discovery may match them after the plant's /clock), then the plant
        # dies without a word.
        assert spin_until(
            lambda: ticks and ticks[-1] >= 300_000_000 and all(map(heard, WATCHERS)), 120
        ), (
            f'the job never ran: /clock up to {ticks[-1:]}, plant alive {plant.alive()}, '
            f'status heard from {[n for n in WATCHERS if heard(n)]}'
        )
        assert all(n.alive() for n in nodes.values())
        os.kill(plant.proc.pid, signal.SIGKILL)
        plant.proc.wait(10)
        spin_until(lambda: not any(n.alive() for n in nodes.values()), TIMEOUT + 30)
        executor.spin_once(timeout_sec=0.5)

    for name, (_module, executable, topic) in WATCHERS.items():
        code, _out, err = nodes[name].wait(timeout=10)
        # It ends by itself with exit code 3 and one line that names the input and the plant,
        # after the input has been silent for input_timeout (the line states how long).
        assert code == 3, f'{name}: exit code {code}\n{err[-2000:]}'
        last = [line for line in err.splitlines() if line.strip()][-1]
        assert last.startswith(f'{executable}: error: nothing on '), last
        assert _silence(last, topic) and min(_silence(last, topic)) >= TIMEOUT, last
        # /diagnostics: a WARN, then an ERROR, in the node's input status, naming both.
        mine = [s for s in statuses if s.name == f'{name}: inputs' and _silence(s.message, topic)]
        levels = [s.level for s in mine]
        assert DiagnosticStatus.WARN in levels and DiagnosticStatus.ERROR in levels, (
            name,
            [(s.level, s.message) for s in mine],
        )
        first_warn = min(_silence(mine[levels.index(DiagnosticStatus.WARN)].message, topic))
        assert WARN_TIME <= first_warn < TIMEOUT, first_warn


def _children(pid: int) -> list[int]:
    """Direct children of a live process (Linux /proc)."""
    out: list[int] = []
    for task in Path(f'/proc/{pid}/task').iterdir():
        out += [int(c) for c in (task / 'children').read_text().split()]
    return out


def _gone(pid: int) -> bool:
    """Ended: no such process, or a zombie waiting for whoever adopted it to reap it."""
    try:
        stat = Path(f'/proc/{pid}/stat').read_text()
    except OSError:
        return True
    return stat.rsplit(')', 1)[1].split()[0] in ('Z', 'X')


@pytest.mark.system
def test_the_nodes_of_a_killed_runner_end_with_it(ros_env, tmp_path) -> None:
    runner = subprocess.Popen(
        [sys.executable, '-m', 'mill_bringup.runner', 'slotting', '--duration', '60'],
        env=ros_env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        cwd=tmp_path,  # its run directory goes there
    )
    children: list[int] = []
    try:
        assert runner.stderr is not None
        for line in runner.stderr:  # said once every node, the plant too, has been started
            if 'started 8 processes' in line:
                break
        children = _children(runner.pid)
        assert len(children) == 8, children
        runner.send_signal(signal.SIGKILL)
        runner.wait(10)
        # Each node gets SIGTERM from the kernel (PR_SET_PDEATHSIG) and ends as on Ctrl-C.
        assert wait_until(lambda: all(_gone(pid) for pid in children), 10), [
            pid for pid in children if not _gone(pid)
        ]
    finally:
        if runner.poll() is None:
            runner.kill()
            runner.wait()
        for pid in children:  # this runner's own nodes only, each in its own session
            if not _gone(pid):
                os.killpg(pid, signal.SIGKILL)
