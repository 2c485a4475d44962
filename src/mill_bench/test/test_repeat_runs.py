"""repeat_runs reads how each run ended from its summary.json, and counts the endings."""

from __future__ import annotations

import json
from pathlib import Path

from mill_bench.repeat_runs import outcome, table


def test_a_runs_ending_is_read_from_its_summary_and_counted(tmp_path: Path) -> None:
    good, lossy, dead = tmp_path / 'good', tmp_path / 'lossy', tmp_path / 'dead'
    for d in (good, lossy):
        d.mkdir()
    (good / 'summary.json').write_text(json.dumps({'missing_samples': {}, 'drive_stalls': {}}))
    (lossy / 'summary.json').write_text(
        json.dumps(
            {
                'missing_samples': {'mill/x/state': 272, 'mill/y/state': 817},
                'drive_stalls': {'count': 5, 'longest_ms': 32.3},
            }
        )
    )
    runs = [
        outcome(good, 0, 'plant: activated\n'),
        outcome(lossy, 3, 'WARNING: mill/x/state: samples missing in the record: 272\n'),
        outcome(dead, 1, ''),  # no summary: its exit code alone
    ]
    assert [r.missing for r in runs] == [0, 1089, 0]
    assert runs[1].stalls == 5 and runs[1].longest_stall_ms == 32.3
    assert 'exit 3, 1089 samples missing, 5 drive stalls, longest 32 ms' in runs[1].line(2)
    text = table(runs)
    assert text.splitlines()[0] == '3 runs: exit 0: 1, exit 1: 1, exit 3: 1'
    assert 'lost a sample of their record: 1' in text
    assert 'with a WARNING line: 1' in text
    assert 'reported a stall: 1, the longest 32 ms' in text


def test_a_lockstep_runs_step_waits_are_counted_over_the_runs(tmp_path: Path) -> None:
    quiet, stalled = tmp_path / 'quiet', tmp_path / 'stalled'
    for d, over, longest in ((quiet, [2, 0, 0], 12.5), (stalled, [5, 1, 1], 2807.5)):
        d.mkdir()
        waits = {
            'over_ms': dict(zip(('10', '100', '1000'), over, strict=True)),
            'longest_ms': longest,
        }
        (d / 'summary.json').write_text(json.dumps({'step_waits': waits}))
    runs = [outcome(quiet, 0, ''), outcome(stalled, 0, '')]
    assert runs[1].waits_over == {10: 5, 100: 1, 1000: 1}
    assert 'steps waiting over 10/100/1000 ms: 5 / 1 / 1' in runs[1].line(2)
    text = table(runs)
    assert 'waited over 10 ms: 7, 100 ms: 1, 1000 ms: 1 (in 1 of 2 runs over 100 ms' in text
    assert 'the longest 2807.5 ms' in text


def test_a_bad_join_period_is_refused_in_one_line(capsys) -> None:  # type: ignore[no-untyped-def]
    import pytest

    from mill_bench import joiner, repeat_runs

    for main, argv in ((repeat_runs.main, ['--join-every', '-1']), (joiner.main, ['0'])):
        with pytest.raises(SystemExit) as info:
            main(argv)
        assert info.value.code == 2
        err = [ln for ln in capsys.readouterr().err.splitlines() if 'error' in ln]
        assert len(err) == 1 and ('join-every' in err[0] or 'period' in err[0]), err
