"""A job as a ROS 2 action (issue 34): the job_server node in its own process, a separate
rclpy ActionClient. A short slotting job gives feedback and its summary; a longer one,
canceled after its first feedback, ends canceled with the axes held by the feed hold."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from test.conftest import ros_node, spin_until

pytestmark = pytest.mark.system
PROGRAM = Path(__file__).resolve().parents[1] / 'config' / 'slotting.ngc'


def _send(client: Any, executor: Any, goal: Any, feedback: list[Any]) -> Any:
    future = client.send_goal_async(goal, feedback_callback=lambda f: feedback.append(f.feedback))
    assert spin_until(executor, future.done, 30), 'the goal was not answered'
    return future.result()


def test_a_job_runs_as_an_action_and_a_cancel_holds_the_feed(
    start_node: Any, tmp_path: Path
) -> None:
    from mill_interfaces.action import RunJob
    from rclpy.action import ActionClient

    server = start_node(
        'mill_bringup.job_server', 'job_server', '-p', f'runs_dir:={tmp_path}', params_file=False
    )
    with ros_node('job_client') as (node, executor):
        client = ActionClient(node, RunJob, '/job_server/run_job')
        assert client.wait_for_server(timeout_sec=30), server.stop()

        bad = _send(client, executor, RunJob.Goal(job='no_such_scenario'), [])
        assert not bad.accepted

        feedback: list[Any] = []
        handle = _send(
            client, executor, RunJob.Goal(job='slotting', duration=0.3, layout='single'), feedback
        )
        assert handle.accepted
        busy = _send(
            client, executor, RunJob.Goal(job='slotting', duration=0.3, layout='single'), []
        )
        assert not busy.accepted  # one job at a time
        result_future = handle.get_result_async()
        assert spin_until(executor, result_future.done, 60), server.stop()[2][-3000:]
        result = result_future.result().result
        summary = json.loads(result.summary_json)
        assert (result.exit_code, result.outcome) == (0, RunJob.Result.OUTCOME_GOOD)
        assert summary['samples'] == 301 and summary['outcome'] == 'good'
        # feedback and result come on topics and services of their own: spin for what is left
        assert spin_until(executor, lambda: bool(feedback), 5), 'no feedback'
        assert all(-1.0 <= f.fraction_done <= 1.0 for f in feedback)

        feedback = []
        # a part program whose plan can hold its feed (the feed override enabled)
        goal = RunJob.Goal(
            job=str(PROGRAM),
            duration=30.0,
            layout='single',
            overrides=['trajectory.feed_override.enabled=true'],
        )
        handle = _send(client, executor, goal, feedback)
        assert handle.accepted
        assert spin_until(executor, lambda: bool(feedback), 60), 'no feedback'
        cancel = handle.cancel_goal_async()
        assert spin_until(executor, cancel.done, 10)
        assert len(cancel.result().goals_canceling) == 1
        result_future = handle.get_result_async()
        assert spin_until(executor, result_future.done, 60), 'no result after the cancel'
        answer = result_future.result()
        result = answer.result
        summary = json.loads(result.summary_json)
        from action_msgs.msg import GoalStatus

        assert answer.status == GoalStatus.STATUS_CANCELED
        assert result.held, server.stop()
        assert (result.exit_code, result.outcome) == (130, RunJob.Result.OUTCOME_INTERRUPTED)
        assert summary['outcome'] == 'interrupted'
        # stopped where the hold came to rest, long before its 30 s; the graph said it held
        (failure,) = summary['failures']
        assert failure['kind'] == 'interrupted' and 0 < failure['time'] < 29.0
        assert 'trajectory: job: job held' in summary['problems']
        assert server.alive()
