"""How a run ends: its exit code (0 good and complete, 1 the job failed, 3 a good job with an
incomplete record) and summary.json, written however it ended."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from mill_analysis.events import DRIVE_SILENT, TRIP, Event
from mill_analysis.record import RunRecord
from mill_analysis.summary import axis_summary
from mill_bringup.runner import cli
from mill_bringup.runner.result import (
    GOOD,
    JOB_FAILED,
    RECORD_INCOMPLETE,
    RunResult,
    format_result,
)
from mill_common.realtime_setup import LISTENER_BELOW


def result(events: list[Event] = (), failing: tuple[str, ...] = (), **kw: Any) -> RunResult:
    rec = RunRecord.empty(11, 0.1)
    rec.signals['position'][:, 0] = 0.0
    rec.signals['reference'][:, 0] = 0.0
    rec.events = list(events)
    values: dict[str, Any] = {
        'scenario': 'slotting',
        'kind': 'axis-realtime',
        'samples': 11,
        'sim_time': 1.0,
        'wall_time': 1.0,
        'real_time_factor': 1.0,
        'steps_per_second': 11.0,
        'cpu_ms_per_step': 0.1,
        'peak_rss_mb': {'plant': 50.0},
        'cpu_ms_per_step_by_process': {},
        'peak_pss_mb': 40.0,
        'domain_id': '7',
        'missing_samples': {},
        'summary': axis_summary(rec, 0.0, failing=failing),
        'record': rec,
    }
    values.update(kw)
    return RunResult(**values)


TRIPPED = Event('x', TRIP, 0.5, 'following error |e| = 2.100 mm > 2 mm: braked', 'x_controller')


def test_the_exit_code_tells_a_failed_job_from_an_incomplete_record() -> None:
    assert result().exit_code == GOOD == 0
    # a trip on a machine fails the job, whatever its record
    failed = result([TRIPPED], failing=(TRIP,), missing_samples={'mill/x/state': 2})
    assert failed.exit_code == JOB_FAILED == 1
    assert format_result(failed).splitlines()[0] == (
        'FAILED: x axis: trip at t = 0.5000 s (x_controller): '
        'following error |e| = 2.100 mm > 2 mm: braked'
    )
    # a lockstep trip is the job's result, not a failure of the run
    assert result([TRIPPED]).exit_code == GOOD
    # a good job whose record lost a sample: both said, a code of its own
    lost = result(missing_samples={'mill/x/state': 2})
    assert lost.exit_code == RECORD_INCOMPLETE == 3
    assert 'WARNING: mill/x/state: samples missing in the record: 2' in format_result(lost)
    assert result(missing_from_bag={'mill/x/state': 1}).exit_code == RECORD_INCOMPLETE
    assert result(foreign={'mill/x/state': 1}).exit_code == RECORD_INCOMPLETE
    assert result(foreign_publishers=['plant: foreign']).exit_code == RECORD_INCOMPLETE


def test_summary_json_holds_the_summary_its_failures_and_the_exit_code() -> None:
    data = json.loads(json.dumps(result([TRIPPED], failing=(TRIP,)).to_json()))
    assert data['exit_code'] == 1
    assert data['failures'] == [TRIPPED.to_json()] and data['events'] == [TRIPPED.to_json()]
    assert [m['axis'] for m in data['metrics']] == ['x']
    assert data['metrics'][0]['stopped_at'] == 0.5


def _main(monkeypatch, tmp_path: Path, *results: RunResult) -> int:
    given = list(results)
    monkeypatch.setattr(cli, 'run', lambda job, run_dir, options: given.pop(0))
    monkeypatch.setattr(cli, 'paper_text', lambda *a, **k: '')
    return cli.main(['slotting', '--timing', 'realtime', '--output', str(tmp_path), '-q'])


@pytest.mark.parametrize(
    ('made', 'code'),
    [
        (result(), 0),
        (result(missing_samples={'mill/x/state': 2}), 3),
        (result([TRIPPED], failing=(TRIP,)), 1),
    ],
    ids=['good', 'incomplete', 'tripped'],
)
def test_run_scenario_writes_the_summary_and_exits_with_its_code(
    monkeypatch, tmp_path: Path, capsys, made: RunResult, code: int
) -> None:
    assert _main(monkeypatch, tmp_path, made) == code
    assert json.loads((tmp_path / 'summary.json').read_text())['exit_code'] == code
    err = capsys.readouterr().err
    if code == 1:
        assert err.splitlines()[-1].endswith('the job failed on the machine (see FAILED above)')
    if code == 3:
        assert "the job went well, but the runner's record of it is incomplete" in err


def test_a_run_a_dead_drive_stopped_writes_its_summary_too(
    monkeypatch, tmp_path: Path, capsys
) -> None:
    said = 'the drive went silent: nothing on mill/x/state from plant for 3.1 s'
    silent = Event('x', DRIVE_SILENT, 1.2, said)
    rec = RunRecord.empty(0, 0.1)  # the drive died before the job started: no sample
    summary = replace(axis_summary(rec, 1.0), failures=(silent,))
    stopped = result(summary=summary, record=rec, error=said)
    assert _main(monkeypatch, tmp_path, stopped) == 1
    data = json.loads((tmp_path / 'summary.json').read_text())
    assert data['failures'][0]['kind'] == 'drive_silent' and data['error'] == said
    out, err = capsys.readouterr()
    assert out.startswith('FAILED: x axis: drive silent at t = 1.2000 s: the drive went silent')
    lines = [line for line in err.splitlines() if line.startswith('run_scenario:')]
    assert lines == [f'run_scenario: error: {said}']  # one line, as before
    assert math.isnan(data['real_time_factor']) or data['real_time_factor'] >= 0


def test_what_stopped_a_run_is_its_typed_failure() -> None:
    from types import SimpleNamespace

    from mill_analysis.events import NODE_DIED, RUN_ERROR, STALL
    from mill_bringup.graph import GraphError
    from mill_bringup.jobs.realtime import DriveSilent
    from mill_bringup.runner.options import RunError, RunFailed
    from mill_bringup.runner.run import failure_of

    class Job:
        def progress(self, source: object) -> float:
            return 2.5

    session = SimpleNamespace(monitor=None)
    died = failure_of(GraphError('node x_controller exited with code 3'), Job(), session)
    assert (died.kind, died.time, died.detail) == (
        NODE_DIED,
        2.5,
        'node x_controller exited with code 3',
    )
    assert failure_of(RunFailed(STALL, 'the run stalled'), Job(), session).kind == STALL
    assert failure_of(RunError('no publisher appeared'), Job(), session).kind == RUN_ERROR
    silent = Event('y', DRIVE_SILENT, 4.0, 'the drive went silent')
    assert failure_of(DriveSilent(silent), Job(), session) is silent
    assert str(DriveSilent(silent)) == 'the drive went silent'  # the line the runner prints


def _ending(kind: str, detail: str) -> RunResult:
    """A run the runner stopped itself (the failure of its Ending), before the job started."""
    event = Event('', kind, math.nan, detail)
    rec = RunRecord.empty(0, 0.1)
    return result(summary=replace(axis_summary(rec, 1.0), failures=(event,)), error=detail)


@pytest.mark.parametrize(
    ('kind', 'outcome', 'code', 'word'),
    [
        ('refused', 'refused', 2, 'REFUSED'),
        ('interrupted', 'interrupted', 130, 'FAILED'),
        ('node_died', 'failed', 1, 'FAILED'),
        ('drive_silent', 'failed', 1, 'FAILED'),
    ],
)
def test_every_ending_writes_its_outcome_and_exit_code(
    monkeypatch, tmp_path: Path, capsys, kind: str, outcome: str, code: int, word: str
) -> None:
    said = f'what ended it ({kind})'
    assert _main(monkeypatch, tmp_path, _ending(kind, said)) == code
    data = json.loads((tmp_path / 'summary.json').read_text())
    assert (data['outcome'], data['exit_code'], data['error']) == (outcome, code, said)
    assert data['failures'][0]['kind'] == kind
    out, err = capsys.readouterr()
    assert out.startswith(f'{word}: {kind.replace("_", " ")}: {said}')
    last = 'run_scenario: interrupted' if code == 130 else f'run_scenario: error: {said}'
    assert err.splitlines()[-1] == last


@pytest.mark.parametrize(
    ('made', 'outcome'),
    [
        (result(), 'good'),
        (result(missing_samples={'mill/x/state': 2}), 'record_incomplete'),
        (result([TRIPPED], failing=(TRIP,)), 'failed'),
    ],
    ids=['good', 'incomplete', 'tripped'],
)
def test_a_completed_run_says_its_outcome_too(
    monkeypatch, tmp_path: Path, made: RunResult, outcome: str
) -> None:
    _main(monkeypatch, tmp_path, made)
    assert json.loads((tmp_path / 'summary.json').read_text())['outcome'] == outcome


@pytest.mark.parametrize(
    ('raised', 'outcome', 'code'),
    [
        (KeyboardInterrupt(), 'interrupted', 130),
        (cli.RunError('no publisher appeared on mill/x/state'), 'failed', 1),
    ],
    ids=['ctrl-c', 'graph'],
)
def test_a_run_that_ended_before_it_had_a_result_writes_its_summary(
    monkeypatch, tmp_path: Path, raised: BaseException, outcome: str, code: int
) -> None:
    """Ctrl-C or an error while the graph was planned or started: no record, but the
    summary says how the run ended."""

    def run(job: object, run_dir: Path, options: object) -> RunResult:
        raise raised

    monkeypatch.setattr(cli, 'run', run)
    argv = ['slotting', '--timing', 'realtime', '--output', str(tmp_path), '-q']
    assert cli.main(argv) == code
    data = json.loads((tmp_path / 'summary.json').read_text())
    assert (data['outcome'], data['exit_code'], data['scenario']) == (outcome, code, 'slotting')
    assert data['metrics'] == [] and data['error']


def test_the_rearmed_axes_and_the_runners_warnings_are_said_and_kept() -> None:
    r = result(rearmed={'y': 'speed 900 mm/s above the limit'}, warnings=['misnamed'])
    text = format_result(r)
    assert 'WARNING: misnamed' in text.splitlines()
    assert (
        "re-armed before the start (--rearm, the drive's ~/release): y (stopped: speed 900 "
        'mm/s above the limit)'
    ) in text.splitlines()
    data = json.loads(json.dumps(r.to_json()))
    assert data['rearmed'] == {'y': 'speed 900 mm/s above the limit'}
    assert data['warnings'] == ['misnamed'] and data['outcome'] == 'good'


def test_the_runner_runs_below_the_graph_when_the_graph_runs_realtime() -> None:
    def priority(*argv: str) -> int:
        return cli.runner_priority(cli.parser().parse_args(['slotting', *argv]))

    assert priority() == 0  # the normal scheduler, as the graph
    # below the graph, above other load
    assert priority('--realtime-priority', '80') == 80 - LISTENER_BELOW
    assert priority('--realtime-priority', '1') == 1
    assert priority('--realtime-priority', '80', '--runner-priority', '0') == 0
    assert priority('--runner-priority', '50') == 50
