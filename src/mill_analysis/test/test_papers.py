"""The papers' metrics on synthetic records whose answers are known."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from mill_analysis.papers import (
    amplitude,
    maharof,
    maharof_metrics,
    move_metrics,
    report,
    rubio_claims,
)
from mill_analysis.record import RunRecord


def record(t: np.ndarray, position: np.ndarray, reference: np.ndarray) -> RunRecord:
    rec = RunRecord.empty(len(t), t[1] - t[0])
    rec['position'][:, 0] = position
    rec['reference'][:, 0] = reference
    rec['torque'][:, 0] = 0.0
    return rec


def test_maharof_metrics_of_a_known_error() -> None:
    t = np.arange(40000) * 1e-4
    e = 1e-4 * np.sin(math.pi * t) + 3e-6 * np.sin(2 * math.pi * 26 * t)  # m
    rec = record(t, -e, np.zeros_like(t))
    rmse, mte, amps = maharof_metrics(rec)
    assert rmse == pytest.approx(math.sqrt((0.1**2 + 0.003**2) / 2), rel=1e-6)
    assert mte == pytest.approx(0.103, rel=1e-3)
    assert amps[0] == pytest.approx(3.0, rel=1e-9)
    assert amps[1] == pytest.approx(0.0, abs=1e-9) and amps[2] == pytest.approx(0.0, abs=1e-9)
    assert amplitude(t, np.cos(2 * math.pi * 52 * t + 1.0), 52.0) == pytest.approx(1.0)


def test_a_short_run_has_no_paper_metrics() -> None:
    t = np.arange(100) * 1e-4
    text = maharof({'pi': record(t, t * 0, t * 0)})
    assert 'no paper metrics' in text
    assert report('unknown', {}) == ''


def test_move_metrics_overshoot_settling_and_iae() -> None:
    t = np.arange(2000) * 1e-3
    ref = np.clip(t / 0.5, 0, 1) * 0.01
    y = ref.copy()
    late = t >= 0.5
    y[late] = 0.01 + 0.001 * np.exp(-(t[late] - 0.5) / 0.05)  # 10 % overshoot, decaying
    m = move_metrics(record(t, y, ref), 0.0, 0.5, 0.5, 1e-4)
    assert m.overshoot == pytest.approx(10.0, rel=1e-6)
    # |e| = 1 mm e^{-s/0.05} falls below 1 µm at s = 0.05 ln 1000 = 0.345 s
    assert m.settling_time == pytest.approx(0.05 * math.log(1000), abs=2e-3)
    assert m.iae == pytest.approx(1.0 * 0.05 * (1 - math.exp(-10)), rel=0.02)


def test_rubio_claims_are_judged_from_the_figures() -> None:
    cases = {
        'ZOH (β = 0)': SimpleNamespace(j_c=100.0),
        'scheme 1': SimpleNamespace(j_c=101.0),
        'scheme 2': SimpleNamespace(j_c=100.0),
    }
    text = rubio_claims({-0.5: 99.0, -0.2: 99.5, 0.0: 100.0, 0.5: 102.0}, cases).splitlines()
    assert 'agrees' in text[0] and 'β = -0.50: -1.00 %' in text[0]
    assert 'disagrees (+1.00 %)' in text[1]
    assert text[2].endswith('agrees (+0.00 %)')
    text = rubio_claims({-0.5: 101.0, 0.0: 100.0}, cases).splitlines()
    assert 'disagrees' in text[0]


def test_every_report_names_the_settings_its_verdicts_rest_on() -> None:
    from mill_analysis.papers import settings_lines

    parameters = {
        'gpi': {'plant': {'sample_period': 1e-4, 'friction_reversal': 'through'}},
        'gpi_1ms': {'plant': {'sample_period': 1e-3, 'friction_reversal': 'through'}},
        'sliding_gpi': {'plant': {'sample_period': 1e-4, 'friction_reversal': 'through'}},
    }
    lines = settings_lines('chavez_conde', parameters).splitlines()
    assert lines == [
        'setting plant.sample_period, sample period [s] (paper: fixed step 1e-3): 0.0001 '
        '(other: gpi_1ms 0.001)',
        "setting plant.friction_reversal, friction reversal (paper: not said): 'through'",
    ]


def test_a_report_warns_of_a_run_that_tripped() -> None:
    from types import SimpleNamespace

    from mill_analysis.events import FAULT, TRIP, Event
    from mill_analysis.papers import braked

    trip = Event('x', TRIP, 0.1, '|e| = 5.1 mm > 5 mm', 'x_controller')
    rec = SimpleNamespace(events=[trip, Event('y', FAULT, 0.2, 'encoder')])
    assert braked({'a': rec, 'b': SimpleNamespace(events=[])}) == (
        'WARNING variant a: x axis: trip at t = 0.1000 s (x_controller): |e| = 5.1 mm > 5 mm; '
        'its figures after that are of a braked axis, not of the law'
    )
