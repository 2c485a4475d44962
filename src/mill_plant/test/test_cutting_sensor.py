"""Simple cutting-force models and the encoder quantizer."""

from __future__ import annotations

import math

import pytest
from mill_plant.cutting import NoCutting, StepForce, StepParams
from mill_plant.sensor import quantize

P = (0.01, -0.02, -0.005)
V = (0.003, 0.0, 0.0)


def test_no_cutting_is_zero() -> None:
    assert NoCutting().force(12.0, P, V) == (0.0, 0.0, 0.0)


def test_step_force_switches_on_at_start_time() -> None:
    step = StepForce(StepParams(force=(10.0, -5.0, 2.5), start_time=0.5))
    assert step.force(0.4999, P, V) == (0.0, 0.0, 0.0)
    assert step.force(0.5, P, V) == (10.0, -5.0, 2.5)
    assert step.force(3.0, P, (0.0, 0.0, 0.0)) == (10.0, -5.0, 2.5)


def test_step_force_refuses_bad_input() -> None:
    with pytest.raises(ValueError):
        StepForce(StepParams(force=(1.0, 2.0), start_time=0.0))
    with pytest.raises(ValueError):
        StepForce(StepParams(force=(1.0, math.nan, 0.0), start_time=0.0))


def test_quantize_rounds_to_nearest_count() -> None:
    assert quantize(0.123456789, 0.0) == 0.123456789
    assert quantize(1.26e-6, 1e-6) == pytest.approx(1e-6, rel=1e-12)
    assert quantize(1.74e-6, 1e-6) == pytest.approx(2e-6, rel=1e-12)
    assert quantize(-1.74e-6, 1e-6) == pytest.approx(-2e-6, rel=1e-12)
    value = quantize(0.0123456, 1e-6)
    assert abs(value - 0.0123456) <= 0.5e-6
    assert abs(value / 1e-6 - round(value / 1e-6)) < 1e-6


def test_quantize_refuses_bad_resolution() -> None:
    with pytest.raises(ValueError):
        quantize(1.0, -1e-6)
    with pytest.raises(ValueError):
        quantize(1.0, math.nan)
