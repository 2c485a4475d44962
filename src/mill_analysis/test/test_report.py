"""report: the command on a bag of another writer (table, Markdown, plots), its metrics
(amplitude at a frequency, largest windowed RMS, feed override) and bad input, one line each."""

from __future__ import annotations

import itertools
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from mill_analysis.bag_run import read_run
from mill_analysis.lockstep_record import record_topics
from mill_analysis.metrics import contour_error, summarize_contour
from mill_analysis.report.analysis import amplitude_at, amplitude_spectrum, analyse, max_window_rms
from mill_analysis.report.plots import contour_planes
from mill_analysis.report.text import feed_text
from mill_analysis.summary import axis_summary
from mill_bag.types import STRING, typestore
from mill_bag.writer import BagWriter

from mill_common import topics

TS = typestore()


def test_feed_override_is_reported_when_the_bag_has_it(foreign_bag) -> None:
    path, _ = foreign_bag('mcap', feed=True)
    run = read_run(path)
    values = [v for _, v in run.feed_override]
    assert values == [1.0 - 0.2 * k / run.n for k in range(0, run.n, 100)]
    text = feed_text(analyse(run, 'f', axis_summary(run.record, 0.1), 0.1, [60.0]))
    assert text == (
        f'feed override: {len(values)} messages, min {min(values):.3f}, '
        f'mean {sum(values) / len(values):.3f}, max 1.000'
    )


def test_report_command_writes_markdown_and_plots(foreign_bag, tmp_path) -> None:
    path, _ = foreign_bag('mcap')
    out = tmp_path / 'report'
    proc = subprocess.run(
        [
            sys.executable,
            '-m',
            'mill_analysis.report',
            str(path),
            '--out',
            str(out),
            '--skip',
            '0.1',
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert 'no feed override in this bag' in proc.stdout
    text = (out / 'report.md').read_text()
    pngs = sorted(p.name for p in out.glob('*.png'))
    assert pngs == sorted(
        [
            'position.png',
            'tracking_error.png',
            'torque.png',
            'disturbance.png',
            'disturbance_zoom.png',
            'cutting_force.png',
            'contour.png',
            'error_spectrum.png',
            'loop_timing.png',
        ]
    )
    for name in pngs:
        assert (out / name).stat().st_size > 10_000, name
        assert f']({name})' in text


def test_report_prints_and_writes_the_contour_error_of_the_bag(foreign_bag, tmp_path) -> None:
    path, made = foreign_bag('mcap')
    rec = read_run(path).record
    contour = contour_error(rec)
    assert contour is not None and contour.axes == 'xyz'
    # The path is a straight line: the contour error is the deviation across it.
    dev = made['position'] - made['reference']
    u = made['reference'][-1] - made['reference'][0]
    u /= np.linalg.norm(u)
    across = np.linalg.norm(dev - np.outer(dev @ u, u), axis=1)
    inner = slice(100, 390)  # not at the path's ends, where its end point is nearer
    np.testing.assert_allclose(contour.distance[inner], across[inner], rtol=1e-9)
    assert np.all(across[inner] < np.linalg.norm(dev, axis=1)[inner])  # below |e|
    summary = summarize_contour(rec, 0.1, contour)
    assert summary is not None and summary.max_error > 1e-6
    out = tmp_path / 'report'
    proc = subprocess.run(
        [
            *(sys.executable, '-m', 'mill_analysis.report', str(path)),
            *('--out', str(out), '--skip', '0.1', '--quiet'),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    line = (
        'contour error (distance to the programmed x-y-z path): '
        f'max {summary.max_error * 1e3:.6f} mm, RMS {summary.rms_error * 1e3:.6f} mm'
    )
    assert line in proc.stdout.splitlines()
    row = f'| {path.name} | x-y-z | {summary.max_error * 1e6:.3f} | {summary.rms_error * 1e6:.3f} |'
    assert row in (out / 'report.md').read_text().splitlines()
    assert (out / 'contour.png').stat().st_size > 10_000


def test_the_side_view_is_drawn_when_the_path_moves_in_z(foreign_bag) -> None:
    path, _ = foreign_bag('mcap')
    report = analyse(run := read_run(path), 'f', axis_summary(run.record, 0.1), 0.1, [60.0])
    assert contour_planes(report) == [(0, 1), (1, 2)]  # z falls 0.4 mm over y's 1.2 mm
    report.run.record['reference'][:, 2] = 0.02  # a flat path: the top view only
    assert contour_planes(report) == [(0, 1)]


def test_progress_reaches_the_end_of_every_phase(foreign_bag) -> None:
    path, _ = foreign_bag('mcap')
    seen: dict[str, list[tuple[int, int | None]]] = {}

    def progress(phase: str, done: int, total: int | None) -> None:
        seen.setdefault(phase, []).append((done, total))

    run = read_run(path, progress=progress)
    assert list(seen) == ['reading', 'decoding']
    # Reading: every message of the bag, against metadata.yaml's count.
    assert seen['reading'][-1] == (run.message_count, run.message_count)
    # Decoding: every message of the record's topics.
    decoded = sum(run.bag.counts[topics.qualify(t)] for t in record_topics(run.axes))
    assert seen['decoding'][-1] == (decoded, decoded)
    for phase in seen.values():
        assert all(b >= a for (a, _), (b, _) in itertools.pairwise(phase))


# -- report metrics -------------------------------------------------------------------------


def test_amplitude_at_reads_tones_between_bins_and_the_spectrum_on_a_bin() -> None:
    dt = 1e-3
    t = np.arange(52_333) * dt
    x = 4e-6 * np.sin(2 * np.pi * 60 * t + 0.3) + 1e-6 * np.sin(2 * np.pi * 120 * t) + 2e-6
    assert amplitude_at(x, dt, 60.0) == pytest.approx(4e-6, rel=1e-3)
    assert amplitude_at(x, dt, 120.0) == pytest.approx(1e-6, rel=1e-3)
    assert amplitude_at(x, dt, 90.0) < 1e-9
    n = 50_000  # 60 Hz on bin 3000
    f, amp = amplitude_spectrum(x[:n], dt)
    assert f[3000] == pytest.approx(60.0)
    assert amp[3000] == pytest.approx(4e-6, rel=1e-3)


def test_max_window_rms_finds_the_burst_and_skips_gaps() -> None:
    x = np.zeros(10_000)
    x[5000:5100] = 3.0  # a 0.1 s burst at 1 kHz
    assert max_window_rms(x, 100) == pytest.approx(3.0)
    assert max_window_rms(x, 200) == pytest.approx(3.0 / math.sqrt(2))
    x[5050] = np.nan  # no full window covers the burst now
    assert max_window_rms(x, 100) == pytest.approx(3.0 * math.sqrt(50 / 100))


# -- bad input ------------------------------------------------------------------------------


def bad_inputs(tmp_path: Path) -> dict[str, tuple[list[str], str]]:
    empty_dir = tmp_path / 'empty_dir'
    empty_dir.mkdir()
    BagWriter(tmp_path / 'empty_bag').close()
    w = BagWriter(tmp_path / 'other_topics')
    chatter = w.add_topic('/chatter', STRING, [])
    for i in range(10):
        w.write(chatter, i, i, bytes(TS.serialize_cdr(TS.types[STRING](data=f'hello {i}'), STRING)))
    w.close()
    (tmp_path / 'junk.mcap').write_bytes(b'not an mcap file at all')
    broken = tmp_path / 'broken_meta'
    broken.mkdir()
    (broken / 'metadata.yaml').write_text('rosbag2_bagfile_information: [unclosed')
    return {
        'missing': ([str(tmp_path / 'no_such_bag')], 'no such bag'),
        'empty directory': ([str(empty_dir)], 'no metadata.yaml and no .mcap file'),
        'empty bag': ([str(tmp_path / 'empty_bag')], 'holds no messages'),
        'no mill topics': ([str(tmp_path / 'other_topics')], 'no /mill/<axis>/state topic'),
        'not mcap': ([str(tmp_path / 'junk.mcap')], 'not an MCAP file'),
        'broken metadata': ([str(broken)], 'not a rosbag2 metadata file'),
        'bad freqs': ([str(tmp_path / 'empty_bag'), '--freqs', '60,abc'], 'not a list of numbers'),
        'bad window': ([str(tmp_path / 'empty_bag'), '--window', '-1'], 'must be > 0'),
    }


BAD = [
    'missing',
    'empty directory',
    'empty bag',
    'no mill topics',
    'not mcap',
    'broken metadata',
    'bad freqs',
    'bad window',
]


@pytest.mark.parametrize('case', BAD)
def test_bad_input_gives_one_line_error(tmp_path, case) -> None:
    args, reason = bad_inputs(tmp_path)[case]
    proc = subprocess.run(
        [sys.executable, '-m', 'mill_analysis.report', *args, '--out', str(tmp_path / 'out')],
        capture_output=True,
        text=True,
        timeout=120,
    )
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode != 0
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith('report: error: ') and reason in lines[0], lines[0]
    assert not (tmp_path / 'out' / 'report.md').exists()
