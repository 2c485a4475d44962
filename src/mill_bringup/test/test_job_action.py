"""The job server's ROS-free part (mill_bringup.job_action): goals checked, the runner's
command line, the feedback from the machine's statuses, the result from summary.json."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
from mill_bringup.job_action import (
    PROBLEMS_KEPT,
    JobGoal,
    JobProgress,
    at_rest,
    clock_topic,
    goal_problem,
    machine_namespace,
    problem_line,
    read_result,
    runner_command,
)
from mill_bringup.runner.result import Outcome

REPO = Path(__file__).resolve().parents[3]
PROGRAM = REPO / 'config' / 'slotting.ngc'


def test_a_known_scenario_and_an_existing_program_are_good_goals() -> None:
    assert goal_problem(JobGoal('slotting', 0.3)) is None
    assert goal_problem(JobGoal(str(PROGRAM), 0.0, ('trajectory.duration=1',), 'single')) is None


@pytest.mark.parametrize(
    ('goal', 'said'),
    [
        (JobGoal('no_such_scenario'), "scenario 'no_such_scenario': no scenario"),
        (JobGoal('/nowhere/part.ngc'), 'program /nowhere/part.ngc: no such file'),
        (JobGoal(''), 'no job: name a scenario or a G-code program file'),
        (JobGoal('slotting', -1.0), 'duration -1.0: must be a finite time >= 0'),
        (JobGoal('slotting', float('nan')), 'duration nan: must be a finite time >= 0'),
        (JobGoal('slotting', 0.3, ('trajectory',)), "override 'trajectory': must be"),
        (JobGoal('slotting', 0.3, (), 'everything'), 'layout: '),
        (JobGoal('slotting', timing='sometimes'), "timing 'sometimes': one of lockstep, realtime"),
        (JobGoal('slotting', stay=True), 'stay: the graph stays up after its job for manual'),
        (JobGoal('slotting', tuning='by ear'), "tuning 'by ear': one of rule"),
        (JobGoal('slotting', timing='lockstep', stay=True), 'stay: '),
    ],
)
def test_a_bad_goal_is_refused_in_one_line(goal: JobGoal, said: str) -> None:
    problem = goal_problem(goal)
    assert problem is not None and problem.startswith(said)
    assert '\n' not in problem


def test_the_runner_command_of_a_scenario_and_of_a_program() -> None:
    cmd = runner_command(JobGoal('slotting', 0.3, ('x_plant.mass=2',), 'single'), Path('r'), '/')
    assert cmd[:3] == [sys.executable, '-m', 'mill_bringup.runner']
    assert cmd[3:] == [
        'slotting',
        '--output',
        'r',
        '--quiet',
        '--duration',
        '0.3',
        '-p',
        'x_plant.mass=2',
        '--layout',
        'single',
    ]
    program = runner_command(JobGoal(str(PROGRAM)), Path('r'), 'machine2')
    assert program[3] == 'slotting'  # a program runs on the slotting scenario
    assert program[program.index('--program') + 1] == str(PROGRAM)
    assert program[-2:] == ['--namespace', '/machine2']
    assert '--duration' not in program  # 0: the scenario's own


def private_scenario(tmp_path: Path, namespace: str = '') -> Path:
    """The slotting scenario asking for a private clock itself (in `namespace`)."""
    text = (REPO / 'config' / 'slotting.yaml').read_text()
    entry = '  ros__parameters:\n    private_clock: true\n'
    if namespace:
        entry += f'    namespace: {namespace}\n'
    path = tmp_path / f'private{namespace}.yaml'
    head = 'mill_scenario:\n  ros__parameters:\n'
    path.write_text(text.replace(head, 'mill_scenario:\n' + entry))
    return path


def test_timing_stay_and_view_of_a_goal_are_the_runners_options() -> None:
    goal = JobGoal(str(PROGRAM), 0.0, (), '', 'realtime', 'rule', stay=True, view=True)
    assert goal_problem(goal) is None
    cmd = runner_command(goal, Path('r'), '/')
    assert cmd[-6:] == ['--timing', 'realtime', '--tuning', 'rule', '--stay', '--view']
    plain = runner_command(JobGoal('slotting'), Path('r'), '/')
    assert not {'--timing', '--tuning', '--stay', '--view'} & set(plain)


def test_the_clock_of_a_goal_is_the_one_its_machine_keeps(tmp_path: Path) -> None:
    goal = JobGoal('slotting', 0.3)
    assert clock_topic(goal, '/', False) == clock_topic(goal, 'machine2', False) == '/clock'
    assert clock_topic(goal, 'machine2', True) == '/machine2/clock'
    assert clock_topic(JobGoal(str(PROGRAM)), '/m', True) == '/m/clock'
    cmd = runner_command(goal, Path('r'), 'machine2', private_clock=True)
    assert cmd[-3:] == ['--namespace', '/machine2', '--private-clock']
    # a scenario that asks for a private clock itself: in the server's namespace, or its own
    own = JobGoal(str(private_scenario(tmp_path)))
    assert clock_topic(own, '/shop/m2', False) == '/shop/m2/clock'
    placed = JobGoal(str(private_scenario(tmp_path, 'machine_b')))
    assert clock_topic(placed, '/', False) == '/machine_b/clock'
    # the machine's namespace: the server's, else the scenario's own (its statuses, services)
    assert machine_namespace(placed, '/') == '/machine_b'
    assert machine_namespace(placed, 'shop') == '/shop'
    assert machine_namespace(goal, '/') == '/'
    cmd = runner_command(placed, Path('r'), '/', private_clock=True)
    assert '--namespace' not in cmd and cmd[-1] == '--private-clock'  # the scenario's namespace
    assert goal_problem(placed) is None
    # no namespace at all: no private clock, and the goal says why in one line
    said = 'a private clock needs a machine namespace: run the job server in one'
    for bad in ((goal, '/', True), (own, '/', False)):
        assert clock_topic(*bad) is None
        problem = goal_problem(*bad)
        assert problem is not None and problem.startswith(said) and '\n' not in problem


def test_feedback_follows_the_clock_and_the_job_status() -> None:
    progress = JobProgress(duration=0.0)
    assert not progress.started
    assert progress.feedback().fraction_done == -1.0  # no end known yet
    progress.on_job_status(
        'machine2/trajectory: job',
        {'state': 'running', 'time': '1.0', 'end_time': '4.0', 'feed_override': '0.5'},
    )
    assert progress.started and progress.trajectory == 'trajectory'
    progress.on_clock(2.0)
    f = progress.feedback()
    assert (f.machine_time, f.fraction_done, f.feed_override) == (2.0, 0.5, 0.5)
    progress.on_job_status(
        'machine2/trajectory: job',
        {'time': '2.5', 'hold': 'held', 'event': 'feed_hold', 'event_where': 'part.ngc:4:1'},
    )
    f = progress.feedback()
    assert (f.line, f.hold, f.machine_time) == ('part.ngc:4:1', 'held', 2.5)
    assert progress.state == 'running'  # the job's state, as last heard
    progress.on_job_status('machine2/trajectory: job', {'time': 'junk', 'end_time': 'inf'})
    assert progress.feedback().fraction_done == 2.5 / 4.0  # a bad value changes nothing
    progress.on_clock(9.0)
    assert progress.feedback().fraction_done == 1.0


def test_the_goal_duration_sets_the_share_done_and_problems_keep_the_latest() -> None:
    progress = JobProgress(duration=3.0)
    progress.on_clock(1.5)
    assert progress.feedback().fraction_done == 0.5
    for k in range(PROBLEMS_KEPT + 2):
        progress.on_problem(f'p{k}')
        progress.on_problem(f'p{k}')  # the same twice in a row: once
    assert progress.feedback().problems == tuple(f'p{k}' for k in range(2, PROBLEMS_KEPT + 2))


def test_problem_lines_of_the_runner() -> None:
    assert problem_line('run_scenario: error: no step within 60 s') is not None
    assert problem_line('FAILED: x tripped at t = 1 s') == 'FAILED: x tripped at t = 1 s'
    assert problem_line('scenario slotting: 301 samples') is None


def test_at_rest_means_every_axis_velocity_zero() -> None:
    assert at_rest([0.0, 0.0, 0.0])
    assert not at_rest([0.0, 1e-6, 0.0])
    assert not at_rest([])  # a sample without velocities says nothing


def test_the_result_is_the_summary_of_the_run(tmp_path: Path) -> None:
    summary = {'scenario': 'slotting', 'outcome': 'good', 'exit_code': 0, 'samples': 301}
    (tmp_path / 'summary.json').write_text(json.dumps(summary))
    result = read_result(tmp_path, 0, '', 'slotting')
    assert result.outcome is Outcome.GOOD and result.exit_code == 0
    assert json.loads(result.summary_json)['samples'] == 301


def test_a_variant_summary_is_found_in_its_directory(tmp_path: Path) -> None:
    (tmp_path / 'scheme1').mkdir()
    summary = {'outcome': 'record_incomplete', 'exit_code': 3}
    (tmp_path / 'scheme1' / 'summary.json').write_text(json.dumps(summary))
    assert read_result(tmp_path, 3, '', 'rubio').outcome is Outcome.RECORD_INCOMPLETE


@pytest.mark.parametrize(
    ('code', 'outcome'),
    [
        (2, Outcome.REFUSED),
        (130, Outcome.INTERRUPTED),
        (-9, Outcome.INTERRUPTED),
        (1, Outcome.FAILED),
    ],
)
def test_a_run_without_a_summary_gets_one_from_its_exit_code(
    tmp_path: Path, code: int, outcome: Outcome
) -> None:
    log = 'Beltran\nrun directory r\nrun_scenario: error: --record: r/bag exists already\n'
    result = read_result(tmp_path, code, log, 'slotting')
    assert result.outcome is outcome and result.exit_code == code
    summary = json.loads(result.summary_json)
    assert summary['outcome'] == outcome.value
    assert summary['error'].endswith('run_scenario: error: --record: r/bag exists already')
