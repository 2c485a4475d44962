"""What the job server (mill_bringup.job_server, the RunJob action) does, without ROS.

A goal names a scenario (run_scenario's name or YAML file) or a G-code part program (a file
ending .ngc, .nc, .gcode, .tap or .cnc, run on the slotting scenario with --program). It is
checked before anything starts (`goal_problem`: one line), run as `python -m
mill_bringup.runner` (`runner_command`), followed from the trajectory's job status and the
machine's warnings on /diagnostics and from /clock (`JobProgress`, the feedback), and its
result read from the run directory's summary.json (`read_result`), whose `outcome` is typed
(runner.result.Outcome). A machine with a private clock (the server's `private_clock`, or the
scenario's own `mill_scenario: private_clock`) keeps it on NAMESPACE/clock, not /clock
(`clock_topic`): the feedback's machine time comes from there. A cancel holds the feed
first; the axes are at rest once every axis velocity of the trajectory's reference is 0
(`at_rest`).
"""

from __future__ import annotations

import json
import math
import sys
from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from mill_bringup.cli import TUNINGS
from mill_bringup.launch_plan import TIMINGS
from mill_bringup.runner.result import INTERRUPTED_CODE, START_REFUSED, Outcome, ended
from mill_bringup.scenario import ScenarioError, check_layout, load
from mill_common import topics

PROGRAM_SUFFIXES = ('.ngc', '.nc', '.gcode', '.tap', '.cnc')
PROGRAM_SCENARIO = 'slotting'  # the scenario a part program runs on (run_scenario --program)
PROBLEMS_KEPT = 5  # the latest problems in the feedback
LOG_LINES = 3  # of the runner's log, in the result of a run that left no summary.json


@dataclass(frozen=True)
class JobGoal:
    job: str  # a scenario's name or YAML file, or a G-code program file
    duration: float = 0.0  # machine time [s]; 0 the scenario's
    overrides: tuple[str, ...] = ()  # run_scenario -p NODE.PARAM=VALUE
    layout: str = ''  # processes, per_axis, single; '' the scenario's
    timing: str = ''  # lockstep, realtime; '' the scenario's
    tuning: str = ''  # rule: the tuning rule's gains; '' the scenario's
    stay: bool = False  # realtime: the graph stays up after the job until canceled
    view: bool = False  # machine_view beside the graph

    @property
    def is_program(self) -> bool:
        return Path(self.job).suffix.lower() in PROGRAM_SUFFIXES


def goal_problem(
    goal: JobGoal, namespace: str = topics.ROOT, private_clock: bool = False
) -> str | None:
    """Why this goal cannot run, in one line (None: it can), for a machine in `namespace`
    asked to keep a private clock or not."""
    if not goal.job.strip():
        return 'no job: name a scenario or a G-code program file'
    if not math.isfinite(goal.duration) or goal.duration < 0:
        return f"duration {goal.duration}: must be a finite time >= 0 [s] (0: the scenario's)"
    for rule in goal.overrides:
        name, eq, _value = rule.partition('=')
        if not eq or not name.strip():
            return f'override {rule!r}: must be NODE.PARAM=VALUE'
    if goal.layout:
        try:
            check_layout(goal.layout)
        except ScenarioError as exc:
            return f'layout: {exc}'
    if goal.timing and goal.timing not in TIMINGS:
        return f"timing {goal.timing!r}: one of {', '.join(TIMINGS)} (empty: the scenario's)"
    if goal.tuning and goal.tuning not in TUNINGS:
        return f"tuning {goal.tuning!r}: one of {', '.join(TUNINGS)} (empty: the scenario's gains)"
    if goal.stay and goal.timing != 'realtime':
        return (
            'stay: the graph stays up after its job for manual commands, which need timing '
            'realtime: give timing realtime'
        )
    if goal.is_program and not Path(goal.job).is_file():
        return f'program {goal.job}: no such file'
    try:
        clock = clock_topic(goal, namespace, private_clock)
    except (ScenarioError, OSError) as exc:
        return f'scenario {goal.job!r}: {" ".join(str(exc).split())}'
    if clock is None:
        return (
            'a private clock needs a machine namespace: run the job server in one '
            '(--ros-args -r __ns:=/NAME)'
        )
    return None


def machine_namespace(goal: JobGoal, namespace: str) -> str:
    """The namespace the goal's machine runs in: the server's (the runner's --namespace), else
    at the root the scenario's own (`mill_scenario: namespace`). ScenarioError: the goal's
    scenario does not load."""
    if topics.namespace(namespace) != topics.ROOT:
        return topics.namespace(namespace)
    return load(PROGRAM_SCENARIO if goal.is_program else goal.job).namespace


def clock_topic(goal: JobGoal, namespace: str, private_clock: bool) -> str | None:
    """The topic of the clock the goal's machine keeps: NAMESPACE/clock with a private clock
    (asked for, or the scenario's own `private_clock`), else /clock, in the machine's
    namespace (machine_namespace). None: a private clock without a namespace (the runner
    refuses it). ScenarioError: the goal's scenario does not load."""
    scen = load(PROGRAM_SCENARIO if goal.is_program else goal.job)
    space = machine_namespace(goal, namespace)
    private = private_clock or scen.private_clock
    if private and topics.namespace(space) == topics.ROOT:
        return None
    return topics.clock(space, private=private)


def runner_command(
    goal: JobGoal, run_dir: Path, namespace: str, private_clock: bool = False
) -> list[str]:
    """The runner's command line for this goal, in this machine namespace (the root: the
    scenario's own), with a private clock or not (goal_problem: only in a namespace)."""
    scenario = PROGRAM_SCENARIO if goal.is_program else goal.job
    cmd = [sys.executable, '-m', 'mill_bringup.runner', scenario, '--output', str(run_dir)]
    cmd.append('--quiet')  # the server reports the progress
    if goal.is_program:
        cmd += ['--program', str(Path(goal.job).resolve())]
    if goal.duration > 0:
        cmd += ['--duration', repr(goal.duration)]
    for rule in goal.overrides:
        cmd += ['-p', rule]
    if goal.layout:
        cmd += ['--layout', goal.layout]
    if goal.timing:
        cmd += ['--timing', goal.timing]
    if goal.tuning:
        cmd += ['--tuning', goal.tuning]
    cmd += ['--stay'] * goal.stay + ['--view'] * goal.view
    if topics.namespace(namespace) != topics.ROOT:
        cmd += ['--namespace', topics.namespace(namespace)]
    if private_clock:  # in the server's namespace, else the scenario's (goal_problem)
        cmd.append('--private-clock')
    return cmd


@dataclass(frozen=True)
class Feedback:
    machine_time: float  # [s]
    fraction_done: float  # 0..1, -1 not known yet
    line: str  # file:line:column of the program's latest event, '' none
    feed_override: float
    hold: str  # running, paused, held ('' not known)
    problems: tuple[str, ...]


@dataclass
class JobProgress:
    """The feedback of a running job, from what the machine says of it."""

    duration: float  # the goal's (0: the end time the trajectory reports)
    machine_time: float = 0.0
    end_time: float = 0.0  # the job's end, as the trajectory reports it
    line: str = ''
    feed_override: float = 1.0
    hold: str = ''
    state: str = ''  # the job's: waiting, running, done, refused ('' not heard yet)
    trajectory: str = ''  # the trajectory node's name, from its status
    problems: deque[str] = field(default_factory=lambda: deque(maxlen=PROBLEMS_KEPT))

    @property
    def started(self) -> bool:
        """Whether the machine runs the job (a tick of its clock or a job status heard)."""
        return self.machine_time > 0 or bool(self.trajectory)

    def on_clock(self, seconds: float) -> None:
        self.machine_time = max(self.machine_time, seconds)

    def on_job_status(self, name: str, values: Mapping[str, str]) -> None:
        """The trajectory's job status (`<trajectory>: job` on /diagnostics)."""
        self.trajectory = topics.parse_status_name(name).node
        self.machine_time = max(self.machine_time, _number(values.get('time'), 0.0))
        self.end_time = _number(values.get('end_time'), self.end_time)
        self.feed_override = _number(values.get('feed_override'), self.feed_override)
        self.hold = values.get('hold', self.hold)
        self.state = values.get('state', self.state)
        self.line = values.get('event_where') or self.line

    def on_problem(self, text: str) -> None:
        """A WARN or ERROR of the machine, or an error line of the runner (each once in a
        row)."""
        if not self.problems or self.problems[-1] != text:
            self.problems.append(text)

    def feedback(self) -> Feedback:
        end = self.duration or self.end_time
        fraction = min(1.0, self.machine_time / end) if end > 0 else -1.0
        return Feedback(
            self.machine_time,
            fraction,
            self.line,
            self.feed_override,
            self.hold,
            tuple(self.problems),
        )


def _number(text: str | None, default: float) -> float:
    try:
        value = float(text) if text is not None else default
    except ValueError:
        return default
    return value if math.isfinite(value) else default


def problem_line(line: str) -> str | None:
    """A line of the runner's output that says something went wrong (None: it does not)."""
    text = line.strip()
    for word in ('error:', 'ERROR:', 'FAILED:', 'REFUSED:', 'WARNING:'):
        if word in text:
            return text
    return None


def at_rest(velocities: Sequence[float], tolerance: float = 1e-9) -> bool:
    """Whether a reference sample's axis velocities are all 0 (a hold has come to rest)."""
    return bool(velocities) and all(abs(v) <= tolerance for v in velocities)


@dataclass(frozen=True)
class JobResult:
    exit_code: int
    outcome: Outcome
    run_dir: Path
    summary_json: str


def read_result(run_dir: Path, exit_code: int, log: str, scenario: str) -> JobResult:
    """The result of a run that ended with this exit code: its summary.json (the last
    variant's, for a scenario with variants), else, for a run refused before it started (no
    summary), a summary of how it ended made here with the runner's last lines."""
    found = sorted(run_dir.glob('*/summary.json'), key=lambda p: p.stat().st_mtime)
    if (run_dir / 'summary.json').is_file():
        found.append(run_dir / 'summary.json')
    for path in reversed(found):
        try:
            text = path.read_text()
            outcome = Outcome(json.loads(text)['outcome'])
        except (OSError, ValueError, KeyError, TypeError):
            continue
        return JobResult(exit_code, outcome, run_dir, text)
    if exit_code == START_REFUSED:
        outcome = Outcome.REFUSED
    elif exit_code == INTERRUPTED_CODE or exit_code < 0:  # < 0: ended by a signal
        outcome = Outcome.INTERRUPTED
    else:
        outcome = Outcome.FAILED
    lines = [line.strip() for line in log.splitlines() if line.strip()]
    said = ' | '.join(lines[-LOG_LINES:]) or f'the runner ended with exit code {exit_code}'
    return JobResult(exit_code, outcome, run_dir, json.dumps(ended(scenario, outcome, said)))
