"""What ends `ros2 launch` with the job: the job_watch node, alone and beside a real graph.

The graph is started from the launch plan (mill_bringup.launch_plan) as launch_ros starts
Nodes: `EXECUTABLE [NODE ...] --ros-args --log-level L [-r __node:=NAME] -r __ns:=NS
--params-file FILE [-r FROM:=TO ...]` (a container gets its nodes as arguments and no node
name), in each layout.
"""

from __future__ import annotations

import importlib.metadata
import itertools
import math
import subprocess
import sys
import time
from pathlib import Path

import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

from mill_bringup import launch_plan
from mill_common import topics
from test.conftest import ros_node, spin_until, wait_until


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


def _viewers_topics(node, ns: str) -> dict[str, list]:
    """Subscribe to what RViz or Foxglove would draw of the machine in `ns`."""
    from mill_common.ros import LATCHED_QOS
    from nav_msgs.msg import Path as PathMsg
    from std_msgs.msg import String

    got: dict[str, list] = {'planned': [], 'trace': [], 'urdf': []}
    qualified = {
        'planned': topics.qualify(topics.PLANNED_PATH, ns),
        'trace': topics.qualify(topics.TOOL_TRACE, ns),
        'urdf': topics.qualify(topics.ROBOT_DESCRIPTION, ns),
    }
    node.create_subscription(PathMsg, qualified['planned'], got['planned'].append, LATCHED_QOS)
    node.create_subscription(PathMsg, qualified['trace'], got['trace'].append, 1000)
    node.create_subscription(String, qualified['urdf'], got['urdf'].append, LATCHED_QOS)
    return got


def _check_viewers_topics(views: dict[str, list], plan: launch_plan.Plan) -> None:
    """The planned path from the job's start to its end; the trace at 20 Hz of the states'
    stamps (t = 0, 0.05, ..., 0.2 s and on: the plant runs on after the job); the URDF
    with the job's travel."""
    from xml.etree import ElementTree

    (planned,) = views['planned']
    assert planned.header.frame_id == 'machine_l/mill_base' and len(planned.poses) == 5000
    trace = views['trace']
    stamps = [p.header.stamp.sec * 10**9 + p.header.stamp.nanosec for p in trace[-1].poses]
    assert len(stamps) >= 5, stamps
    # one point per 50 ms of the states' stamps (the plant's 1 ms grid: 50 ms exactly)
    assert {b - a for a, b in itertools.pairwise(stamps)} == {50_000_000}, stamps
    # every point measured during the job (its 0.2 s: the planned path's) on the programmed
    # path (its points 0.12 µm apart), within 0.1 mm
    path = [(p.pose.position.x, p.pose.position.y, p.pose.position.z) for p in planned.poses]
    assert path[-1][1] - path[0][1] == pytest.approx(0.2 * 0.003, rel=1e-9)  # 0.2 s at 3 mm/s
    for pose, stamp in zip(trace[-1].poses, stamps, strict=True):
        if stamp > 200_000_000:
            continue
        here = (pose.pose.position.x, pose.pose.position.y, pose.pose.position.z)
        assert min(math.dist(here, p) for p in path) < 1e-4, here
    (urdf,) = views['urdf']
    travel = plan.config.values('trajectory')['travel.min']  # type: ignore[union-attr]
    joints = ElementTree.fromstring(urdf.data).iter('joint')
    assert [float(j.find('limit').get('lower')) for j in joints] == travel


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
    required = [n.name for n in plan.nodes if n.required]
    try:
        with ros_node('viewer') as (node, executor):
            views = _viewers_topics(node, 'machine_l')
            # as launch does: the first required node to end ends the launch
            deadline = time.monotonic() + 300
            while all(procs[r].poll() is None for r in required):
                assert time.monotonic() < deadline, 'nothing ended the launch within 300 s'
                executor.spin_once(timeout_sec=0.1)
            ended = {r: procs[r].poll() for r in required if procs[r].poll() is not None}
            assert 'job_watch' in ended, f'{ended} ended the launch before job_watch: ' + next(
                procs[r].communicate(timeout=30)[1][-3000:] for r in ended
            )

            # what is still on its way, and the latched topics of a viewer that comes late
            # (the plant runs on after the job: the trace grows on)
            def enough() -> bool:
                return bool(views['planned']) and len(views['trace'][-1:][0].poses) >= 5

            spin_until(executor, lambda: views['trace'] and enough(), timeout=60)
            spin_until(executor, lambda: views['urdf'], timeout=30)
        _out, err = procs['job_watch'].communicate(timeout=600)
        assert procs['job_watch'].returncode == 0, err
        assert 'job done at t = 0.2' in err, err
        assert procs[clock].poll() is None  # still running: launch would now stop it
        _check_viewers_topics(views, plan)
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
