"""What each kind of job says of its runs: the kind of record its bag holds (for `report`)
and what goes before the paper's verdicts of a run."""

from __future__ import annotations

import pytest
from mill_bringup.cli import set_timing
from mill_bringup.jobs.registry import JOB_KINDS, job_for
from mill_bringup.runner.cli import paper_text

from mill_analysis import papers, records
from mill_bringup import scenario


def test_every_job_kind_names_its_kind_of_record() -> None:
    assert {kind.KIND: kind.RECORD for kind in JOB_KINDS} == {
        'axis': records.AXIS,
        'axis-realtime': records.AXIS_REALTIME,
        'force': records.FORCE,
    }


def test_only_a_realtime_run_notes_that_its_verdicts_are_no_reproduction(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(papers, 'report', lambda paper, recs: f'{paper}: {sorted(recs)}')
    lockstep = job_for(scenario.load('maharof').variant('pi'))
    scen = scenario.load('maharof').variant('pi')
    set_timing(scen, 'realtime')
    realtime = job_for(scen)
    assert not lockstep.PAPER_NOTE and realtime.PAPER_NOTE.startswith('note: a realtime run: ')
    assert paper_text('maharof', {'a': lockstep}, {'a': None}) == "maharof: ['a']"
    both = paper_text('maharof', {'a': lockstep, 'b': realtime, 'c': realtime}, {'a': None})
    assert both == f"{realtime.PAPER_NOTE}\nmaharof: ['a']"  # said once
