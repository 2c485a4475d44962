"""An operator drives a job through ROS from a separate rclpy client (issue 34, item 5).

The job is a goal of the RunJob action: the job_server node, in a process of its own, runs
it with run_scenario (the graph in processes of its own), a G-code part of this test's with
an M0. The operator is a node of the test process in a ROS context of its own; it calls the
trajectory's services as `ros2 service call` would and reads where the reference takes the
axes on /mill/reference, the measured axes on mill/<axis>/state, and the action's feedback.

While the job runs: a jog is refused with its one-line reason, a second feed hold and a
resume with nothing to resume are refused; a feed hold brings the reference to rest on the
programmed line, strictly before its end, and the measured axes within the controllers'
following-error bound of it; resume goes on; the program reaches its M0 and waits there at
rest, exactly at the programmed point; resume goes on to the end of the program, and the
result is the run's summary, good. The feedback says `held`, then `paused` with the M0's
line.

Timing lockstep: a feed hold and an M0 pause need a plan that leaves the room to
decelerate along the path, which only a lockstep job with `feed_override.enabled` has
(mill_trajectory.config.build_schedule refuses pauses and the feed override with timing
realtime). The manual moves (jog by an increment, home, MDI, a bad MDI line) need timing
realtime and a job that has ended while its graph is still up (run_scenario --stay): a
second graph, test/test_operator_by_hand.py.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest
from mill_bringup.scenario import load

from mill_common import topics
from test.conftest import ros_node, spin_until

pytestmark = pytest.mark.system

# From the slotting job's start (x -75, y -105, z -5 mm): 6 mm in +y at 1 mm/s, held on the
# way; an M0; 2 mm in +x. Short moves: the graph's start and end take most of the test. A
# lockstep graph of one process runs about 3x real time on a quiet machine: the 6 s of the
# first line leave the operator about 2 s of wall time to see it move and hold it (at
# 5 mm/s, 0.4 s, and 4 runs in 9 saw the line end before the operator had heard the graph).
PART = (
    'G21 G90 G17 G54\n'
    'G1 Y-99 F60 (6 mm in +y at 1 mm/s: the feed is held on the way)\n'
    'M0 (check the slot)\n'
    'G1 X-73 (2 mm in +x)\n'
    'M30\n'
)
START = (-0.075, -0.105, -0.005)  # [m] the slotting job's start, where the part begins
PAUSE = (-0.075, -0.099, -0.005)  # [m] where the M0 stops the tool
END = (-0.073, -0.099, -0.005)  # [m] the program's end
EXACT = 1e-12  # [m] the reference: the planned line itself, to rounding
TIMEOUT = 60.0  # [s] for anything to happen on this loaded machine
LOCKSTEP_JOG = (
    "timing lockstep replays a job on the plant's clock, sample by sample: manual commands "
    'need timing realtime'
)


class Operator:
    """The operator's services, the reference and the measured axes, on one rclpy node."""

    def __init__(self, node: Any, executor: Any) -> None:
        from mill_interfaces.srv import Jog
        from sensor_msgs.msg import JointState
        from std_srvs.srv import Trigger
        from trajectory_msgs.msg import JointTrajectory

        self.node, self.executor = node, executor
        self.types = {'jog': Jog}
        self.clients = {
            name: node.create_client(self.types.get(name, Trigger), f'/trajectory/{name}')
            for name in ('feed_hold', 'resume', 'jog')
        }
        self.reference: Any = None  # the newest message
        self.measured: dict[str, float] = {}
        node.create_subscription(JointTrajectory, topics.REFERENCE, self._on_reference, 10)
        for axis in 'xyz':
            node.create_subscription(
                JointState, topics.state(axis), lambda m, a=axis: self._on_state(a, m), 10
            )

    def _on_reference(self, msg: Any) -> None:
        self.reference = msg

    def _on_state(self, axis: str, msg: Any) -> None:
        self.measured[axis] = msg.position[0]

    def call(self, name: str, **request: Any) -> tuple[bool, str]:
        from std_srvs.srv import Trigger

        client = self.clients[name]
        assert client.wait_for_service(timeout_sec=TIMEOUT), f'no /trajectory/{name}'
        future = client.call_async(self.types.get(name, Trigger).Request(**request))
        assert spin_until(self.executor, future.done, TIMEOUT), f'{name}: no answer'
        answer = future.result()
        return bool(answer.success), str(answer.message)

    def moving(self) -> bool:
        msg = self.reference
        return msg is not None and any(any(p.velocities[:3]) for p in msg.points)

    def still(self) -> tuple[float, ...] | None:
        """Where the reference stands if every point of its newest message is at rest
        there (None: it moves)."""
        msg = self.reference
        if msg is None or not msg.points:
            return None
        first = tuple(msg.points[0].positions[:3])
        rest = all(
            tuple(p.positions[:3]) == first and not any(p.velocities[:3]) for p in msg.points
        )
        return first if rest else None


def job_server_with(start_node: Any, tmp_path: Path, name: str, program: str) -> tuple:
    """The part program written to tmp_path/name, the controllers' following-error bound
    [m], and a job_server process whose goals run under tmp_path."""
    part = tmp_path / name
    part.write_text(program)
    bound = load('slotting').parameters('x_controller')['following_error_limit']
    server = start_node(
        'mill_bringup.job_server', 'job_server', '-p', f'runs_dir:={tmp_path}', params_file=False
    )
    return part, bound, server


def test_an_operator_holds_resumes_and_is_refused_through_ros_while_a_job_runs(
    start_node: Any, tmp_path: Path
) -> None:
    from action_msgs.msg import GoalStatus
    from mill_interfaces.action import RunJob
    from rclpy.action import ActionClient

    part, bound, server = job_server_with(start_node, tmp_path, 'part.ngc', PART)
    goal = RunJob.Goal(
        job=str(part),
        duration=120.0,  # machine time, an upper bound: the job ends where its path ends
        layout='single',
        # a plan with room to hold the feed; the M0 waits for the operator (far longer than
        # this test: a pause that ended by itself would leave the M0's resume refused)
        overrides=['trajectory.feed_override.enabled=true', 'trajectory.gcode.resume_after=600'],
    )
    feedback: list[Any] = []
    with ros_node('operator') as (node, executor):
        op = Operator(node, executor)
        client = ActionClient(node, RunJob, '/job_server/run_job')
        assert client.wait_for_server(timeout_sec=TIMEOUT), server.stop()
        sent = client.send_goal_async(goal, feedback_callback=lambda f: feedback.append(f.feedback))
        assert spin_until(executor, sent.done, TIMEOUT)
        handle = sent.result()
        assert handle.accepted
        result_future = handle.get_result_async()

        # The first line runs: hold its feed on the way.
        assert spin_until(executor, op.moving, TIMEOUT), server.stop()[2][-3000:]
        ok, said = op.call('feed_hold')
        assert (ok, said) == (True, 'feed hold: decelerating to rest along the path')
        assert spin_until(executor, lambda: op.still() is not None, TIMEOUT)
        held = op.still()
        assert held is not None
        # on the programmed line, short of its end: x and z as programmed, y on the way
        assert (held[0], held[2]) == pytest.approx((START[0], START[2]), abs=EXACT)
        assert START[1] < held[1] < PAUSE[1]
        assert spin_until(executor, lambda: any(f.hold == 'held' for f in feedback), TIMEOUT)
        # the measured axes come to rest there, within the controllers' following-error bound
        assert spin_until(executor, lambda: len(op.measured) == 3, TIMEOUT)
        for i, axis in enumerate('xyz'):
            assert abs(op.measured[axis] - held[i]) < bound, (axis, op.measured, held)

        # Refused while the job runs, each in one line; nothing moves.
        assert op.call('jog', axis='x', distance=0.001) == (False, LOCKSTEP_JOG)
        assert op.call('feed_hold') == (False, 'the feed is held already: call resume to go on')
        assert op.still() == held

        ok, said = op.call('resume')
        assert (ok, said) == (True, 'feed hold released: back to the feed')
        assert spin_until(executor, op.moving, TIMEOUT)

        # The M0: the reference waits at rest exactly at the programmed point.
        assert spin_until(executor, lambda: op.still() == pytest.approx(PAUSE, abs=EXACT), TIMEOUT)
        assert spin_until(executor, lambda: any(f.hold == 'paused' for f in feedback), TIMEOUT)
        paused = next(f for f in feedback if f.hold == 'paused')
        assert paused.line == f'{part}:3:1'  # the M0's file:line:column
        ok, said = op.call('resume')
        assert (ok, said) == (True, f'resumed after the pause at {part}:3:1 (M0: program stop)')
        # nothing left to resume, while the last line runs
        assert op.call('resume') == (False, 'nothing to resume: no pause and no feed hold')

        # On to the end of the program: the result is the run's summary.
        assert spin_until(executor, result_future.done, TIMEOUT), server.stop()[2][-3000:]
        answer = result_future.result()
        result = answer.result
        summary = json.loads(result.summary_json)
        assert answer.status == GoalStatus.STATUS_SUCCEEDED, summary
        assert (result.exit_code, result.outcome) == (0, RunJob.Result.OUTCOME_GOOD)
        assert summary['failures'] == [] and summary['missing_samples'] == {}
        assert op.still() == pytest.approx(END, abs=EXACT)
        # the tracking error of the whole job, holds included, within the bound
        worst = max(m['max_error'] for m in summary['metrics'])  # [m], t >= the skip
        assert math.isfinite(worst) and worst < bound
        assert server.alive()
