"""Sinusoidal reference (Maharof 2018: 10 mm amplitude at 0.5 Hz): values and derivatives."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mill_common.parameters import ParameterError, validate_all
from mill_trajectory.sinusoid import Sinusoid, SinusoidParams


def test_paper_defaults() -> None:
    path = Sinusoid.from_parameters(validate_all(Sinusoid.PARAMETERS, {}))
    assert path.end_time == 4.0
    xs = [path.sample(t).position[0] for t in np.linspace(0.0, 4.0, 4001)]
    assert max(xs) == pytest.approx(0.01)  # amplitude 10 mm, 20 mm peak to peak
    assert min(xs) == pytest.approx(-0.01)
    assert path.sample(0.5).position == pytest.approx((0.01, 0.0, 0.0))  # quarter of 2 s
    assert path.sample(0.0).velocity[0] == pytest.approx(0.01 * math.pi)
    assert path.sample(1.0).position[1:] == (0.0, 0.0)


def test_derivatives_are_exact() -> None:
    path = Sinusoid(
        SinusoidParams(
            center=(0.001, 0.0, 0.0),
            amplitude=(0.01, 0.002, 0.003),
            frequency=(0.5, 2.0, 0.0),
            phase=(0.3, 1.0, 0.7),
            duration=5.0,
        )
    )
    h = 1e-5
    for t in np.linspace(0.1, 4.9, 49):
        s, lo, hi = path.sample(t), path.sample(t - h), path.sample(t + h)
        for i in range(3):
            vel_fd = (hi.position[i] - lo.position[i]) / (2 * h)
            acc_fd = (hi.velocity[i] - lo.velocity[i]) / (2 * h)
            assert s.velocity[i] == pytest.approx(vel_fd, rel=1e-6, abs=1e-12)
            assert s.acceleration[i] == pytest.approx(acc_fd, rel=1e-6, abs=1e-10)
    # z has f = 0: a constant c + A sin φ.
    assert path.sample(2.0).position[2] == pytest.approx(0.003 * math.sin(0.7))


def test_holds_before_start_and_after_end() -> None:
    path = Sinusoid(SinusoidParams(amplitude=(0.01, 0.0, 0.0), duration=1.25, start_time=2.0))
    assert path.end_time == 3.25
    before = path.sample(1.0)
    assert before.position == (0.0, 0.0, 0.0) and before.velocity == (0.0, 0.0, 0.0)
    after = path.sample(9.0)
    assert after.position[0] == pytest.approx(0.01 * math.sin(2 * math.pi * 0.5 * 1.25))
    assert after.velocity == after.acceleration == (0.0, 0.0, 0.0)


def test_bad_values() -> None:
    with pytest.raises(ParameterError, match='frequency'):
        validate_all(Sinusoid.PARAMETERS, {'frequency': [0.5, -1.0, 0.5]})
    with pytest.raises(ValueError, match='duration'):
        Sinusoid(SinusoidParams(duration=0.0))
