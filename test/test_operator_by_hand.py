"""After a realtime job the operator moves the machine by hand through ROS (issue 34, item 5).

Manual moves need timing realtime (a lockstep job replays on the plant's clock) and a job
that has ended while its graph is up: a RunJob goal with `stay` (run_scenario --stay) keeps
the graph up after the job until the goal is canceled. The job_server runs the goal in a
process of its own; from a separate rclpy node (test.test_operator.Operator), once the job's
line has come to rest: a jog by an increment, set home there, one MDI line, a bad MDI line
refused in one line, home; the reference rests exactly at each target, the measured axes
within the controllers' following-error bound of it. The cancel then ends the stay: the
result is canceled, with the axes at rest and the summary of the complete job, good.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest

from test.conftest import ros_node, spin_until
from test.test_operator import EXACT, TIMEOUT, Operator, job_server_with

# Realtime, the axes on the wall clock: alone on the machine (scripts/test.sh, serial).
pytestmark = [pytest.mark.system, pytest.mark.serial]

# A realtime job of one short line, then the machine by hand (no M0: timing realtime does
# not pause).
LINE = 'G21 G90 G17 G54\nG1 Y-104 F300 (1 mm in +y at 5 mm/s)\nM30\n'
# Realtime at 100 Hz, the gains of the tuning rule for it, rapids (MDI G0, home) at 10 mm/s:
# a command late by a few periods leaves the axis within the drive's guard. Beside other
# test runs (load average 12-20 on the 2 cores, stalls of the graph's process up to 0.4 s)
# the drive still stopped an axis whose commands stalled longer in 3 runs of 8 (at 1 kHz in
# every run): alone on the machine.
REALTIME = {
    'timing': 'realtime',
    'tuning': 'rule',
    'overrides': ['*.sample_period=0.01', 'trajectory.gcode.max_velocity=[0.01, 0.01, 0.01]'],
}
LINE_END = (-0.075, -0.104, -0.005)  # [m] from the slotting job's start (-75, -105, -5 mm)
JOG = 0.003  # [m] of x, by increment
MDI = (-0.070, -0.100)  # [m] x, y of the MDI line's rapid


def test_after_a_realtime_job_the_graph_stays_up_and_the_operator_jogs_homes_and_runs_mdi(
    start_node: Any, tmp_path: Path
) -> None:
    from action_msgs.msg import GoalStatus
    from mill_interfaces.action import RunJob
    from mill_interfaces.srv import Mdi
    from rclpy.action import ActionClient

    part, bound, server = job_server_with(start_node, tmp_path, 'line.ngc', LINE)
    goal = RunJob.Goal(job=str(part), layout='single', stay=True, **REALTIME)
    with ros_node('operator') as (node, executor):
        op = Operator(node, executor)
        op.types['mdi'] = Mdi
        for name in ('mdi', 'home', 'set_home'):
            op.clients[name] = node.create_client(
                op.types.get(name, _trigger()), f'/trajectory/{name}'
            )

        def settled_at(target: tuple[float, ...]) -> bool:
            still = op.still()
            return still is not None and still == pytest.approx(target, abs=EXACT)

        def measured_near(target: tuple[float, ...]) -> bool:
            got = [op.measured.get(a, math.inf) for a in 'xyz']
            return all(abs(g - t) < bound for g, t in zip(got, target, strict=True))

        client = ActionClient(node, RunJob, '/job_server/run_job')
        assert client.wait_for_server(timeout_sec=TIMEOUT), server.stop()
        sent = client.send_goal_async(goal)
        assert spin_until(executor, sent.done, TIMEOUT)
        handle = sent.result()
        assert handle.accepted
        # The job's line runs, then the reference rests at its end: the job is done (its
        # start, one line away, may come before this node hears the reference).
        assert spin_until(executor, lambda: settled_at(LINE_END), TIMEOUT), server.stop()
        ok, said = op.call('jog', axis='x', distance=JOG)
        while not ok and said.startswith('a job is running'):  # its end, by the wall clock
            ok, said = op.call('jog', axis='x', distance=JOG)
        assert ok, said
        jogged = (LINE_END[0] + JOG, *LINE_END[1:])
        assert spin_until(executor, lambda: settled_at(jogged), TIMEOUT)
        assert spin_until(executor, lambda: measured_near(jogged), TIMEOUT), op.measured

        ok, said = op.call('set_home')
        assert ok, said
        ok, said = op.call('mdi', line=f'G0 X{1e3 * MDI[0]:g} Y{1e3 * MDI[1]:g}')
        assert ok, said
        there = (*MDI, LINE_END[2])
        assert spin_until(executor, lambda: settled_at(there), TIMEOUT)
        assert spin_until(executor, lambda: measured_near(there), TIMEOUT), op.measured
        assert op.call('mdi', line='G1 X5 Y') == (False, 'mdi:1:7: word Y has no number')
        ok, said = op.call('home')
        assert ok, said
        assert spin_until(executor, lambda: settled_at(jogged), TIMEOUT)
        assert spin_until(executor, lambda: measured_near(jogged), TIMEOUT), op.measured

        # The cancel ends the stay: nothing moves by hand, the runner ends as for a
        # complete job.
        cancel = handle.cancel_goal_async()
        assert spin_until(executor, cancel.done, TIMEOUT)
        assert len(cancel.result().goals_canceling) == 1
        result_future = handle.get_result_async()
        assert spin_until(executor, result_future.done, TIMEOUT), 'no result after the cancel'
        answer = result_future.result()
    result = answer.result
    summary = json.loads(result.summary_json)
    assert answer.status == GoalStatus.STATUS_CANCELED
    assert result.held, summary  # the reference at rest when the runner was stopped
    assert (result.exit_code, result.outcome) == (0, RunJob.Result.OUTCOME_GOOD), summary
    assert summary['failures'] == []
    assert server.alive()


def _trigger() -> Any:
    from std_srvs.srv import Trigger

    return Trigger
