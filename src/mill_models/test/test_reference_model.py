"""Reference model of Rubio 2013 eq. (7) and its continuous response."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal
from mill_models.reference_model import (
    ContinuousReference,
    natural_frequency,
    reference_model,
    reference_state_space,
)

T = 60.0 / 715.0  # one spindle revolution at 715 rpm (Rubio 2013 §5)
DAMPING = 0.7
OMEGA_N = natural_frequency(3.0 * T)  # T_r = three spindle periods


def test_paper_natural_frequency_and_unit_dc_gain() -> None:
    assert pytest.approx(9.93, abs=0.005) == OMEGA_N  # §5: ω_n ≈ 9.93 rad/s
    num, den = reference_model(DAMPING, OMEGA_N)
    assert np.polyval(num, 0.0) / np.polyval(den, 0.0) == 1.0
    a, b, c = reference_state_space(DAMPING, OMEGA_N)
    np.testing.assert_allclose(np.poly(a), den)  # same poles as the transfer function
    assert -c @ np.linalg.solve(a, b) == pytest.approx(1.0)


def test_continuous_reference_is_the_step_response_of_eq7() -> None:
    ref = ContinuousReference(DAMPING, OMEGA_N)
    ref.begin(1200.0)
    t = np.linspace(0.0, 0.5, 51)
    _, expected = scipy.signal.step(reference_model(DAMPING, OMEGA_N), T=t)
    np.testing.assert_allclose(ref.values(t), 1200.0 * expected, atol=1e-8)
    ref.advance(0.3)
    ref.begin(1200.0)
    np.testing.assert_allclose(ref.values(np.array([0.5])), 1200.0 * expected[-1], atol=1e-8)


def test_non_finite_reference_is_refused() -> None:
    ref = ContinuousReference(DAMPING, OMEGA_N)
    with pytest.raises(ValueError, match='finite'):
        ref.begin(float('nan'))
