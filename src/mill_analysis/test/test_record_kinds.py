"""report reads a bag through the kind of record it names (run_scenario --record writes its job
kind's), a bag that names none through the kind its topics and job status tell."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from mill_analysis.report.kinds import (
    AxisRecords,
    ForceRecords,
    LockstepAxisRecords,
    RealtimeAxisRecords,
    ReportOptions,
    kind_of,
)
from mill_bag.errors import BagError

from mill_analysis import bag_meta
from mill_common import topics

OPTIONS = ReportOptions(skip=0.1, window=0.1, freqs=[60.0], namespace=None, quiet=True)


def report(*args: str | Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, '-m', 'mill_analysis.report', *map(str, args)],
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_every_kind_of_record_has_its_reader() -> None:
    assert sorted(bag_meta.NAMES) == sorted(
        k.NAME for k in (LockstepAxisRecords, RealtimeAxisRecords, ForceRecords)
    )
    assert bag_meta.bag_notes(bag_meta.FORCE) == {bag_meta.KEY: 'force'}
    with pytest.raises(ValueError, match='no kind of record'):
        bag_meta.bag_notes('axis-lockstep')


def test_a_bag_that_names_its_kind_is_read_as_that_kind(foreign_bag) -> None:
    # The job status has a start stamp, as a realtime job's: the bag's own word counts.
    path, rec = foreign_bag('mcap', start_ns=0, notes=bag_meta.bag_notes(bag_meta.AXIS))
    kind = kind_of(path)
    assert isinstance(kind, LockstepAxisRecords)
    run = kind.read(path, 'run', OPTIONS).run
    assert not run.realtime and run.n == rec.t.size


def test_a_bag_that_names_no_kind_is_told_by_its_job_status(foreign_bag) -> None:
    lockstep, _ = foreign_bag('mcap')
    assert type(kind_of(lockstep)) is AxisRecords
    assert not kind_of(lockstep).read(lockstep, 'a', OPTIONS).run.realtime
    path, _ = foreign_bag('sqlite3', start_ns=0)
    assert type(kind_of(path)) is AxisRecords
    assert kind_of(path).read(path, 'b', OPTIONS).run.realtime


def test_a_realtime_bag_without_its_start_is_refused(foreign_bag) -> None:
    path, _ = foreign_bag('mcap', notes=bag_meta.bag_notes(bag_meta.AXIS_REALTIME))
    assert isinstance(kind_of(path), RealtimeAxisRecords)
    with pytest.raises(BagError, match='a realtime run without its start'):
        kind_of(path).read(path, 'run', OPTIONS)


def test_a_kind_report_does_not_know_is_one_line(foreign_bag, tmp_path: Path) -> None:
    path, _ = foreign_bag('mcap', notes={bag_meta.KEY: 'spindle'})
    with pytest.raises(BagError, match="kind 'spindle', which this report does not know"):
        kind_of(path)
    proc = report(path, '--out', tmp_path / 'out')
    assert proc.returncode == 1
    assert proc.stderr.startswith('report: error: ') and proc.stderr.count('\n') == 1


def test_bags_of_the_axis_and_the_force_job_do_not_share_a_report(
    foreign_bag, tmp_path: Path
) -> None:
    axis, _ = foreign_bag('mcap', notes=bag_meta.bag_notes(bag_meta.AXIS))
    force, _ = foreign_bag('sqlite3', notes=bag_meta.bag_notes(bag_meta.FORCE))
    proc = report(axis, force, '--out', tmp_path / 'out')
    assert proc.returncode == 1
    assert proc.stderr == (
        'report: error: force-job bags and axis-job bags cannot share one report\n'
    )


def test_report_names_every_topic_a_realtime_bag_lacks_samples_of(foreign_bag) -> None:
    # The recorder lost samples 5 and 6 of y's state and 7 of the ground truth.
    path, rec = foreign_bag(
        'mcap',
        start_ns=0,
        notes=bag_meta.bag_notes(bag_meta.AXIS_REALTIME),
        drop={topics.state('y'): {5, 6}, topics.GROUND_TRUTH: {7}},
    )
    kind = kind_of(path)
    run = kind.read(path, 'rt', OPTIONS)
    assert run.run.realtime and run.run.n == rec.t.size
    assert run.run.missing == {topics.state('y'): 2, topics.GROUND_TRUTH: 1}
    warnings = [line for line in kind.table([run]).splitlines() if 'WARNING' in line]
    assert warnings == [
        'WARNING: mill/y/state: samples missing in the record: 2',
        'WARNING: mill/ground_truth: samples missing in the record: 1',
    ]
    markdown = kind.markdown([run], [], ['rt'])
    assert all(f'- rt: {w}' in markdown for w in warnings)


def test_a_bag_that_lost_nothing_says_nothing_of_losses(foreign_bag) -> None:
    path, _ = foreign_bag('mcap', start_ns=0, notes=bag_meta.bag_notes(bag_meta.AXIS_REALTIME))
    kind = kind_of(path)
    run = kind.read(path, 'rt', OPTIONS)
    assert run.run.missing == {}
    assert 'WARNING' not in kind.table([run]) and 'WARNING' not in kind.markdown([run], [], [])


def test_a_lockstep_bag_names_the_samples_it_lacks_too(foreign_bag) -> None:
    path, _ = foreign_bag('mcap', drop={topics.estimate('z'): {3}})
    run = kind_of(path).read(path, 'ls', OPTIONS)
    assert not run.run.realtime
    assert 'WARNING: mill/z/estimate: samples missing in the record: 1' in kind_of(path).table(
        [run]
    )


PER_SAMPLE = [
    *(f(a) for a in 'xyz' for f in (topics.state, topics.estimate, topics.joint_command)),
    topics.GROUND_TRUTH,
    topics.CUTTING_FORCE,
]


@pytest.mark.parametrize('kind_name', [bag_meta.AXIS, bag_meta.AXIS_REALTIME])
def test_a_bag_cut_short_says_what_it_holds_and_lacks(foreign_bag, kind_name) -> None:
    # The recorder was killed after sample 199 of the job's 401 (0.4 s).
    realtime = kind_name == bag_meta.AXIS_REALTIME
    path, _ = foreign_bag(
        'mcap',
        start_ns=0 if realtime else None,
        notes=bag_meta.bag_notes(kind_name),
        drop={t: range(200, 401) for t in [*PER_SAMPLE, topics.REFERENCE]},
    )
    kind = kind_of(path)
    run = kind.read(path, 'cut', OPTIONS)
    table = kind.table([run]).splitlines()
    assert run.run.held == (200, 0.199)
    if realtime:  # the drive's ticks after the bag's last state, at its rate
        assert table[0].endswith('(200 samples, the last at t = 0.199 s of 0.400 s, T = 1 ms)')
        assert run.run.missing == {t: 201 for t in [*map(topics.state, 'xyz'), topics.GROUND_TRUTH]}
        assert 'the bag ends at t = 0.199 s' in kind.table([run])
    else:
        assert table[0].endswith(
            "(200 of the job's 401 samples, the last at t = 0.199 s of 0.400 s, T = 1 ms)"
        )
        assert run.run.missing == dict.fromkeys([*PER_SAMPLE, topics.REFERENCE], 201)
        command = topics.joint_command('y')
        line = f'WARNING: {command}: samples missing in the record: 201 (k = 200–400)'
        assert line in table
        assert f'- cut: {line}' in kind.markdown([run], [], ['cut'])
        assert '| 200 of 401 | 1 ms | 0.199 s |' in kind.markdown([run], [], ['cut'])


def test_a_bag_that_names_its_topics_owners_leaves_out_what_they_did_not_send(
    foreign_bag,
) -> None:
    # The writer names no sender (frame_id ''): a bag that says the plant sends the states of
    # y has none of them from the plant.
    notes = {
        **bag_meta.bag_notes(bag_meta.AXIS),
        **bag_meta.owners_note({topics.state('y'): 'plant'}, '/'),
    }
    path, rec = foreign_bag('mcap', notes=notes)
    run = kind_of(path).read(path, 'owned', OPTIONS).run
    assert run.record.foreign == {topics.state('y'): rec.t.size}
    assert run.missing == {topics.state('y'): rec.t.size}
    assert f'ERROR: {topics.state("y")}: {rec.t.size} messages left out of the record: ' in (
        '\n'.join(run.losses())
    )
    assert bag_meta.owners(notes, '/') == {topics.state('y'): 'plant'}
    assert (
        bag_meta.owners(notes, '/machine2') == {}
        and bag_meta.owners({bag_meta.OWNERS: '['}, '/') == {}
    )
