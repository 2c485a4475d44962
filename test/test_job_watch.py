"""What ends `ros2 launch` with the job: the job_watch node, alone and beside a real graph.

The graph is started from the launch plan (mill_bringup.launch_plan) as launch_ros starts
Nodes: `EXECUTABLE [NODE ...] --ros-args --log-level L [-r __node:=NAME] -r __ns:=NS
--params-file FILE [-r FROM:=TO ...]` (a container gets its nodes as arguments and no node
name), in each layout.
"""

from __future__ import annotations

import importlib.metadata
import subprocess
import sys
import time
from pathlib import Path

import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

from mill_bringup import launch_plan
from mill_common import topics
from test.conftest import ros_node, wait_until


def console_script(package: str, executable: str) -> str:
    """The executable of a package's console script, as `ros2 run` and launch start it."""
    for ep in importlib.metadata.entry_points(group='console_scripts'):
        if ep.name == executable and ep.value.startswith(package + '.'):
            return str(Path(sys.executable).with_name(executable))
    raise AssertionError(f'{package} has no executable {executable!r}')


def _status(machine: str, state: str) -> DiagnosticArray:
    values = [KeyValue(key='state', value=state), KeyValue(key='time', value='1.0')]
    status = DiagnosticStatus(
        name='trajectory: job', message=f'job {state}', hardware_id=machine, values=values
    )
    return DiagnosticArray(status=[status])


@pytest.mark.system
def test_job_watch_ends_on_its_own_machines_done_only(start_node) -> None:
    watch = start_node('mill_bringup.job_watch', 'job_watch', '-r', '__ns:=/machine2')
    with ros_node('status_source') as (node, executor):
        pub = node.create_publisher(DiagnosticArray, topics.DIAGNOSTICS, 10)
        assert wait_until(lambda: pub.get_subscription_count() > 0, 60), 'job_watch never came'
        for machine, state in (('/machine2', 'running'), ('/machine3', 'done'), ('/', 'done')):
            pub.publish(_status(machine, state))
            executor.spin_once(timeout_sec=0.5)
        time.sleep(1.0)
        assert watch.alive(), 'ended on a status that is not its machine reporting done'
        pub.publish(_status('/machine2', 'done'))
        code, _out, err = watch.wait(timeout=30)
    assert code == 0, err
    assert 'job_watch: job done at t = 1.0 s' in err


def launched(n: launch_plan.NodePlan) -> list[str]:
    """The command launch_ros starts a planned node or container with."""
    cmd = [console_script(n.package, n.executable), *n.nodes, '--ros-args', *n.ros_arguments]
    if not n.nodes:  # a container keeps its nodes' own names
        cmd += ['-r', f'__node:={n.name}']
    cmd += ['-r', f'__ns:={n.namespace}']
    for f in n.parameters:
        cmd += ['--params-file', f]
    for source, target in n.remappings:
        cmd += ['-r', f'{source}:={target}']
    return cmd


@pytest.mark.system
@pytest.mark.parametrize('layout', ['processes', 'per_axis', 'single'])
def test_the_launch_plan_ends_with_the_job(ros_env, tmp_path: Path, layout: str) -> None:
    # per_axis and single: issue 34 (mill_container found no mill_scenario launch list in
    # the launch's parameter file: rc 2, and the plant timed out waiting for it: rc 3).
    params = tmp_path / 'short.yaml'
    params.write_text('/**/trajectory:\n  ros__parameters:\n    duration: 0.2\n')
    plan = launch_plan.plan('slotting', 'machine_l', str(params), '', 'warn', layout, 'true')
    launch_plan.write_parameters(plan, str(tmp_path))
    procs = {}
    for n in plan.nodes:
        procs[n.name] = subprocess.Popen(
            launched(n), env=ros_env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
        )
    clock = next(n.name for n in plan.nodes if n.required and n.name != 'job_watch')
    try:
        _out, err = procs['job_watch'].communicate(timeout=600)
        assert procs['job_watch'].returncode == 0, err
        assert 'job done at t = 0.2' in err, err
        assert procs[clock].poll() is None  # still running: launch would now stop it
    finally:
        for p in procs.values():
            if p.poll() is None:
                p.terminate()
        hung = []
        for name, p in procs.items():
            try:
                p.communicate(timeout=30)
            except subprocess.TimeoutExpired:  # none is left to slow the tests after this one
                p.kill()
                p.communicate()
                hung.append(name)
        assert not hung, f'still running 30 s after SIGTERM: {hung}'
