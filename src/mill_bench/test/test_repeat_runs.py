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
