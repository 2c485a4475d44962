"""Job server node: a job as a ROS 2 action (mill_interfaces/action/RunJob on ~/run_job).

    ros2 run mill_bringup job_server
    ros2 action send_goal --feedback /job_server/run_job mill_interfaces/action/RunJob \
        "{job: slotting, duration: 0.3}"

A goal runs `python -m mill_bringup.runner` in a process of its own, in this node's
ROS_DOMAIN_ID and namespace, with its run directory under `runs_dir`; with `private_clock`
(in a namespace) the machine keeps its clock on NAMESPACE/clock (run_scenario
--private-clock), as it does when the goal's scenario asks for a private clock itself.
Feedback (twice a second once the job runs, and once at its end): the machine time (from the
clock the goal's machine keeps, mill_bringup.job_action.clock_topic), the share done,
the program line of the latest event, the feed override and hold state (the trajectory's
job status on /diagnostics), the latest warnings of the machine and error lines of the
runner. The result: the runner's exit code,
its summary.json's outcome and the summary. One goal at a time; a bad goal is rejected
with one line (mill_bringup.job_action.goal_problem). A cancel is a controlled stop: the
trajectory's ~/feed_hold (a deceleration along the path), until every axis velocity of its
reference is 0 or `hold_timeout` passed, then SIGINT to the runner, which stops the graph
and closes its bag; the result says whether the axes were held (`held`). A goal with `stay`
(timing realtime) keeps its graph up after the job for manual commands until it is canceled;
a cancel then stops any manual move along its path (~/jog_stop) instead, and the runner ends
as for a complete job once the reference is at rest.
"""

from __future__ import annotations

import datetime as dt
import os
import signal
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from mill_common.declared import ParamSet, param
from mill_common.node_main import run_node
from mill_common.parameters import ParamSpec, boolean, in_range, text
from mill_common.ros_params import NodeParameters
from mill_interfaces.action import RunJob
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.action.server import ServerGoalHandle
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.task import Future
from rosgraph_msgs.msg import Clock
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory

from mill_bringup.job_action import (
    JobGoal,
    JobProgress,
    JobResult,
    at_rest,
    clock_topic,
    goal_problem,
    machine_namespace,
    problem_line,
    read_result,
    runner_command,
)
from mill_bringup.runner.result import JOB_FAILED
from mill_common import topics

FEEDBACK_PERIOD = 0.5  # [s]
STOP_TIMEOUT = 60.0  # [s] after SIGINT before SIGKILL (the runner closes its bag first)
AXIS_COUNT = 3  # x, y, z: the first joints of the reference (the spindle follows)


@dataclass(frozen=True)
class JobServerParams(ParamSet):
    PREFIX: ClassVar[str] = ''
    runs_dir: str = param(
        'runs',
        "where each goal's run directory is made (runs_dir/job-TIME-N)",
        text,
        read_only=True,
    )
    hold_timeout: float = param(
        10.0,
        'a cancel waits this long for the axes to come to rest under the feed hold before it '
        'stops the runner',
        in_range(0.0, 600.0),
        unit='s',
    )
    private_clock: bool = param(
        False,
        "each goal's machine keeps its simulation clock on NAMESPACE/clock instead of /clock "
        '(run_scenario --private-clock), so that machines in other namespaces of the domain '
        'run at the same time; needs a namespace (-r __ns:=/NAME)',
        boolean,
    )


def parameter_specs() -> list[tuple[str, ParamSpec]]:
    return JobServerParams.named_specs()


class Run:
    """The goal under way: the runner's process and what is known of it."""

    def __init__(self, handle: ServerGoalHandle, goal: JobGoal, run_dir: Path) -> None:
        self.handle = handle
        self.goal = goal
        self.run_dir = run_dir
        self.progress = JobProgress(goal.duration)
        self.done: Future = Future()
        self.proc: subprocess.Popen[bytes] | None = None
        self.log = run_dir / 'runner.log'
        self.log_read = 0
        self.stage = 'running'  # running, holding, stopping
        self.hold_deadline = 0.0
        self.rested = False
        self.stopped_at = 0.0
        self.private_clock = False  # run_scenario --private-clock
        self.namespace = topics.ROOT  # the machine's: the server's, else the scenario's
        self.manual = False  # canceled while staying up after the job: ~/jog_stop


class JobServer(Node):
    def __init__(self, **options: Any) -> None:
        super().__init__('job_server', **options)
        self.params = NodeParameters(self, parameter_specs(), lambda _v: None)
        self._run: Run | None = None
        self._count = 0
        qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
        self.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, self._on_status, qos)
        self._machine_clock: Any = None  # the clock of the goal's machine, once a goal runs
        self._reference: Any = None  # subscribed while a cancel holds the feed
        self._hold_client: Any = None
        self._server = ActionServer(
            self,
            RunJob,
            '~/run_job',
            execute_callback=self._execute,
            goal_callback=self._on_goal,
            cancel_callback=self._on_cancel,
        )
        self.create_timer(FEEDBACK_PERIOD, self._tick)
        self.get_logger().info(f'ready: {self.resolve_topic_name("~/run_job")} (RunJob)')

    # -- goals ---------------------------------------------------------------------------
    def _on_goal(self, request: Any) -> GoalResponse:
        goal = JobGoal(
            request.job,
            float(request.duration),
            tuple(request.overrides),
            request.layout,
            request.timing,
            request.tuning,
            bool(request.stay),
            bool(request.view),
        )
        if self._run is not None or self._count < 0:
            self.get_logger().warning(
                f'goal {goal.job!r} rejected: the job {self._run.goal.job!r} is running; one '
                'job at a time'
                if self._run is not None
                else f'goal {goal.job!r} rejected: shutting down'
            )
            return GoalResponse.REJECT
        private = self.params.values['private_clock']
        problem = goal_problem(goal, self.get_namespace(), private)
        if problem is not None:
            self.get_logger().warning(f'goal rejected: {problem}')
            return GoalResponse.REJECT
        self._count += 1
        stamp = dt.datetime.now().strftime('%Y%m%d-%H%M%S')
        run_dir = Path(self.params.values['runs_dir']) / f'job-{stamp}-{self._count}'
        self._run = Run(None, goal, run_dir)  # type: ignore[arg-type]  # the handle comes next
        self._run.private_clock = private
        self._run.namespace = machine_namespace(goal, self.get_namespace())
        clock = clock_topic(goal, self.get_namespace(), private)
        if clock is not None:  # None: goal_problem refused the goal
            self._follow_clock(clock)
        return GoalResponse.ACCEPT

    def _follow_clock(self, topic: str) -> None:
        """Take the machine time of the goal's machine from this clock topic."""
        if self._machine_clock is not None and self._machine_clock.topic_name == topic:
            return
        if self._machine_clock is not None:
            self.destroy_subscription(self._machine_clock)
        self._machine_clock = self.create_subscription(Clock, topic, self._on_clock, 1)

    def _on_cancel(self, handle: ServerGoalHandle) -> CancelResponse:
        run = self._run
        if run is None or run.handle is not handle or run.stage != 'running':
            return CancelResponse.REJECT
        return CancelResponse.ACCEPT

    async def _execute(self, handle: ServerGoalHandle) -> Any:
        run = self._run
        assert run is not None
        run.handle = handle
        cmd = runner_command(run.goal, run.run_dir, self.get_namespace(), run.private_clock)
        try:
            run.run_dir.mkdir(parents=True, exist_ok=True)
            with run.log.open('wb') as log:
                run.proc = subprocess.Popen(
                    cmd, stdout=log, stderr=subprocess.STDOUT, env=os.environ
                )
        except OSError as exc:  # runs_dir not writable, no interpreter: the goal fails
            said = f'the runner could not start: {exc}'
            self.get_logger().error(f'job {run.goal.job!r}: {said}')
            run.done.set_result(read_result(run.run_dir, JOB_FAILED, said, run.goal.job))
        else:
            self.get_logger().info(f'job {run.goal.job!r} started: {run.run_dir}')
        result: JobResult = await run.done
        self._run = None
        self._stop_reference()
        msg = RunJob.Result(
            exit_code=result.exit_code,
            outcome=result.outcome.value,
            held=run.rested,
            run_dir=str(result.run_dir),
            summary_json=result.summary_json,
        )
        said = f'job {run.goal.job!r} ended: {result.outcome.value} (exit code {result.exit_code})'
        if handle.is_cancel_requested:
            handle.canceled()
            self.get_logger().info(f'{said}, canceled; axes held: {run.rested}')
        elif result.exit_code == 0:
            handle.succeed()
            self.get_logger().info(said)
        else:
            handle.abort()
            self.get_logger().warning(said)
        return msg

    # -- following the run ---------------------------------------------------------------
    def _tick(self) -> None:
        run = self._run
        if run is None or run.proc is None or run.done.done():
            return
        self._read_log(run)
        code = run.proc.poll()
        if code is not None:
            self._feedback(run, last=True)  # however short the job, heard of or not
            log = run.log.read_text(errors='replace') if run.log.exists() else ''
            scenario = run.goal.job if not run.goal.is_program else Path(run.goal.job).name
            run.done.set_result(read_result(run.run_dir, code, log, scenario))
            return
        if run.stage == 'running' and run.handle.is_cancel_requested:
            self._start_hold(run)
        if run.stage == 'holding' and (run.rested or time.monotonic() > run.hold_deadline):
            if not run.rested:
                self.get_logger().warning(
                    'cancel: the axes did not come to rest within hold_timeout '
                    f'({self.params.values["hold_timeout"]:g} s) of the feed hold; stopping the '
                    'runner anyway'
                )
            self._stop_runner(run)
        if run.stage == 'stopping' and time.monotonic() - run.stopped_at > STOP_TIMEOUT:
            run.proc.kill()
        self._feedback(run)

    def _feedback(self, run: Run, last: bool = False) -> None:
        if not (run.progress.started or last):  # the graph is starting: nothing to tell yet
            return
        f = run.progress.feedback()
        run.handle.publish_feedback(
            RunJob.Feedback(
                machine_time=f.machine_time,
                fraction_done=f.fraction_done,
                line=f.line,
                feed_override=f.feed_override,
                hold=f.hold,
                problems=list(f.problems),
            )
        )

    def _read_log(self, run: Run) -> None:
        if not run.log.exists():
            return
        with run.log.open('rb') as f:
            f.seek(run.log_read)
            data = f.read()
        end = data.rfind(b'\n') + 1
        run.log_read += end
        for line in data[:end].decode(errors='replace').splitlines():
            problem = problem_line(line)
            if problem is not None:
                run.progress.on_problem(problem)

    def _on_status(self, msg: DiagnosticArray) -> None:
        run = self._run
        if run is None:
            return
        for status in msg.status:
            if not topics.from_machine(status.hardware_id, run.namespace):
                continue
            if topics.part_of(status.name) == topics.JOB_STATUS:
                run.progress.on_job_status(status.name, {kv.key: kv.value for kv in status.values})
            if status.level in (DiagnosticStatus.WARN, DiagnosticStatus.ERROR):
                run.progress.on_problem(f'{status.name}: {status.message}')

    def _on_clock(self, msg: Any) -> None:
        run = self._run
        if run is not None:
            run.progress.on_clock(msg.clock.sec + msg.clock.nanosec * 1e-9)

    # -- a controlled stop ---------------------------------------------------------------
    def _start_hold(self, run: Run) -> None:
        trajectory = run.progress.trajectory or 'trajectory'
        # A job done and staying up (goal.stay): what may move is a manual move, stopped
        # along its path by ~/jog_stop; else the job, held by ~/feed_hold.
        run.manual = run.goal.stay and run.progress.state == 'done'
        stop = 'jog_stop' if run.manual else 'feed_hold'
        service = topics.qualify(f'{trajectory}/{stop}', run.namespace)
        run.stage = 'holding'
        run.hold_deadline = time.monotonic() + self.params.values['hold_timeout']
        self.get_logger().info(f'cancel: {stop} ({service}), then the runner stops')
        self._reference = self.create_subscription(
            JointTrajectory, topics.REFERENCE, lambda m: self._on_reference(run, m), 10
        )
        if self._hold_client is None or self._hold_client.srv_name != service:
            self._hold_client = self.create_client(Trigger, service)
        if not self._hold_client.service_is_ready():
            self.get_logger().warning(f'cancel: no {service}; stopping the runner at once')
            self._stop_runner(run)
            return
        future = self._hold_client.call_async(Trigger.Request())
        future.add_done_callback(lambda f: self._held(run, f))

    def _held(self, run: Run, future: Future) -> None:
        answer = future.result()
        if answer is not None and not answer.success and run.manual:
            # no manual move under way: the runner stops once the reference is seen at rest
            self.get_logger().info(f'cancel: {answer.message}')
        elif answer is None or not answer.success:
            said = 'no answer' if answer is None else answer.message
            self.get_logger().warning(f'cancel: feed hold refused ({said}); stopping the runner')
            if run.stage == 'holding':
                self._stop_runner(run)

    def _on_reference(self, run: Run, msg: Any) -> None:
        if run.stage != 'holding' or not msg.points:
            return
        velocities = list(msg.points[0].velocities)[:AXIS_COUNT]
        if at_rest(velocities) and (run.manual or run.progress.hold == 'held'):
            run.rested = True

    def _stop_runner(self, run: Run) -> None:
        self._stop_reference()
        run.stage = 'stopping'
        run.stopped_at = time.monotonic()
        if run.proc is not None and run.proc.poll() is None:
            run.proc.send_signal(signal.SIGINT)

    def _stop_reference(self) -> None:
        if self._reference is not None:
            self.destroy_subscription(self._reference)
            self._reference = None

    def destroy_node(self) -> None:
        run, self._count = self._run, -1
        if run is not None and run.proc is not None and run.proc.poll() is None:
            run.proc.send_signal(signal.SIGINT)  # the runner stops its graph, closes its bag
            try:
                run.proc.wait(STOP_TIMEOUT)
            except subprocess.TimeoutExpired:
                run.proc.kill()
        self._server.destroy()
        super().destroy_node()


def main(argv: list[str] | None = None) -> int:
    return run_node(
        JobServer,
        'job_server',
        'Runs a job (a scenario or a G-code program) as the ROS 2 action ~/run_job '
        '(mill_interfaces/action/RunJob): feedback twice a second, the summary as result; a '
        'cancel holds the feed, then stops the run.',
        parameter_specs(),
        argv,
    )


if __name__ == '__main__':
    raise SystemExit(main())
