"""A run's summary as one value: the text and the JSON print from it, one window for every
figure (the approach left out), a tripped axis's figures up to its trip."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from mill_analysis.events import BRAKED, DRIVE_SILENT, TRIP, Event
from mill_analysis.metrics import Window
from mill_analysis.record import RunRecord
from mill_analysis.summary import (
    AxisSummary,
    DriveFigures,
    ForceSummary,
    PredictionComparison,
    axis_summary,
    force_summary,
)

DT = 0.001


def tracking_run(n: int = 3001, approach: float = 0.0, error: float = 20e-6) -> RunRecord:
    """x and y follow a circle of 10 mm from `approach` s on, `error` [m] outside it; before
    it, an approach from 40 mm away on a straight line, 3 mm behind its reference."""
    rec = RunRecord.empty(n, DT)
    t = rec.t
    s = np.clip(t - approach, 0.0, None)
    ref = np.stack([0.01 * np.cos(s), 0.01 * np.sin(s), np.zeros_like(s)], axis=1)
    pos = ref * (1 + error / 0.01)
    pos[:, 2] = 0.0
    before = t < approach
    if before.any():
        start = np.array([0.05, 0.0, 0.0])
        frac = (t[before] / approach)[:, None]
        ref[before] = start + frac * (ref[~before][0] - start)
        pos[before] = ref[before] + np.array([0.003, 0.0, 0.0])
    rec.signals['reference'][:] = ref
    rec.signals['position'][:] = pos
    rec.signals['estimate_disturbance'][:] = 0.0
    rec.signals['true_disturbance'][:] = 1.0
    return rec


def test_the_text_and_the_json_agree_because_the_text_prints_the_value() -> None:
    rec = tracking_run()
    rec.events = [
        Event('y', TRIP, 2.5, 'following error |e| = 2.100 mm > 2 mm: braked', 'y_controller')
    ]
    drive = DriveFigures(
        'the drive',
        {
            a: dict.fromkeys(('late_fraction', 'longest_late_run'), 0.0)
            | {
                'latency_median_ms': 0.4,
                'latency_p99_ms': 0.9,
                'latency_max_ms': 1.5,
            }
            for a in 'xyz'
        },
        overruns=3,
        ticks=600,
    )
    prediction = PredictionComparison('tuned.yaml', {'x': 2e-5}, {'x': 5e-6})
    summary = axis_summary(
        rec, 1.0, failing=(TRIP,), predictions=[prediction], drive=drive, start_stamp_ns=7
    )
    data = json.loads(json.dumps(summary.to_json()))  # as summary.json holds it
    back = AxisSummary.from_json(data)
    assert back.text() == summary.text()
    assert back == summary
    text = summary.text()
    assert 'x 20 / 5 (4.00x)' in text and 'WARNING: x tracked more than 2x worse' in text
    assert 'y axis: trip at t = 2.5000 s (y_controller): following error' in text
    assert 'ticked more than half a period late 3 times of 600 (0.50 %)' in text
    assert [e['kind'] for e in data['failures']] == ['trip']
    assert [m['axis'] for m in data['metrics']] == ['x', 'y', 'z']


def test_a_force_summary_reads_back_from_its_json_too() -> None:
    summary = force_summary(
        12.5,
        np.array([1.0, 0.8, np.nan]),
        np.array([0.1, 0.1, 0.2]),
        [Event('', DRIVE_SILENT, math.nan, 'gone')],
    )
    back = ForceSummary.from_json(json.loads(json.dumps(summary.to_json())))
    assert back.text() == summary.text()
    assert summary.text().startswith('J_c (Rubio 2013 eq. 14) = 12.5 N²·s; override: mean 0.9000')
    assert summary.beta_switches == 1 and summary.betas == (0.1, 0.2)
    empty = force_summary(math.nan, np.array([]), np.array([]))  # a run stopped at once
    assert math.isnan(empty.mean_override)


def test_a_tripped_axis_has_its_figures_up_to_its_trip_and_says_so() -> None:
    rec = tracking_run()
    trip_at = 2.0
    after = rec.t >= trip_at
    # braked at the trip: y stands still while its reference goes on (a large error), or
    # the drive holds it at NaN: neither counts
    rec.signals['position'][after, 1] = rec.signals['position'][np.argmax(after) - 1, 1]
    rec.signals['position'][rec.t >= 2.8, 0] = np.nan
    rec.events = [
        Event('y', TRIP, trip_at, 'd', 'y_controller'),
        Event('y', BRAKED, 2.3, 'brake request (invalid command)', 'plant'),
        Event('x', BRAKED, 2.8, 'brake request (invalid command)', 'plant'),
    ]
    summary = axis_summary(rec, 1.0)
    x, y, z = summary.axes
    assert y.stopped_at == trip_at and y.stop == 'tripped'
    assert x.stopped_at == 2.8 and x.stop == 'braked' and z.stopped_at is None
    # before the trip only: the 20 µm outside the circle, shared by x and y
    assert 15e-6 < y.max_error <= 20e-6 * (1 + 1e-9)
    assert 15e-6 < x.max_error <= 20e-6 * (1 + 1e-9)
    lines = summary.text().splitlines()
    assert lines[2].endswith('tripped at t = 2.0000 s: figures up to then')
    assert lines[1].endswith('braked at t = 2.8000 s: figures up to then')
    assert ' 0.000000 ' not in lines[2]
    # the contour error of every axis at once ends at the first stop
    assert summary.contour_until == trip_at
    assert summary.contour is not None and summary.contour.max_error < 25e-6
    assert lines[4].endswith('up to t = 2.0000 s')


def test_an_axis_whose_record_ends_at_its_trip_prints_nan_never_zero() -> None:
    rec = tracking_run()
    rec.signals['position'][:, 2] = np.nan
    rec.signals['position'][:, 1][rec.t >= 0.5] = np.nan  # nothing of y after 0.5 s
    rec.events = [Event('y', TRIP, 0.5, 'd')]
    (_, y) = axis_summary(rec, 1.0).axes
    assert math.isnan(y.max_error) and math.isnan(y.rms_error)
    assert '0.000000' not in axis_summary(rec, 1.0).text().splitlines()[2]


def test_the_approach_is_left_out_of_every_figure_and_of_the_contour_path() -> None:
    approach = 0.8
    rec = tracking_run(n=3801, approach=approach)
    summary = axis_summary(rec, 1.0, approach=approach)
    assert summary.window == Window(approach + 1.0)
    x = summary.axes[0]
    # the approach's 3 mm is in no figure: the per-axis maxima and the contour error agree
    assert 15e-6 < x.max_error <= 20e-6 * (1 + 1e-9)
    assert summary.contour is not None
    assert summary.contour.max_error == pytest.approx(20e-6, rel=1e-2)
    assert (
        summary.text().splitlines()[0].endswith('(t >= 1.8 s: 1 s after the approach of 0.800 s)')
    )
    # Counting the approach gave a contour error of millimetres beside per-axis figures of
    # micrometres: one window for both.
    with_it = axis_summary(rec, 0.0)
    assert with_it.contour is not None and with_it.contour.max_error > 1e-3


def test_the_lockstep_header_is_unchanged() -> None:
    summary = axis_summary(tracking_run(), 1.0)
    assert summary.text().splitlines()[0] == (
        'axis   max |e| [mm]   RMS e [mm]   RMS(xi_hat - xi) [m/s^2]   RMS xi [m/s^2]   (t >= 1 s)'
    )
