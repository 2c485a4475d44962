"""The record of a force job: J_c of Rubio 2013 eq. (14) from a recorded force stream."""

from __future__ import annotations

import numpy as np
import pytest
from mill_analysis.force_record import continuous_cost, smooth_pieces
from mill_models.reference_model import ContinuousReference

DAMPING, OMEGA_N = 0.7, 2.5 / (3 * 60.0 / 715.0)  # Rubio 2013 §2.3 defaults at 715 rpm


def test_a_stream_that_follows_the_reference_model_costs_nothing() -> None:
    times = np.linspace(0.0, 1.0, 65)
    ref = ContinuousReference(DAMPING, OMEGA_N)
    ref.begin(1200.0)
    exact = ref.values(times)
    ns = np.rint(times * 1e9).astype(np.int64)
    assert continuous_cost(ns, exact, 1200.0, DAMPING, OMEGA_N) < 1e-12
    assert continuous_cost(ns, exact + 10.0, 1200.0, DAMPING, OMEGA_N) == (
        pytest.approx(100.0, rel=1e-9)
    )


def test_pieces_split_at_repeated_points() -> None:
    ns = np.array([0, 10, 20, 20, 30, 40, 41, 50, 60])
    pieces = smooth_pieces(ns, np.arange(9.0))
    assert [len(t) for t, _ in pieces] == [3, 3, 3]
    assert pieces[1][1].tolist() == [3.0, 4.0, 5.0]
