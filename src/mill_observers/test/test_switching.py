"""Observer hand-over: the estimate continues, then fades into the new observer's."""

from __future__ import annotations

import math

import pytest
from mill_common.signals import Estimate
from mill_observers.switching import EstimateBlend


def test_estimate_holds_at_the_switch_and_fades_to_the_new_one() -> None:
    blend = EstimateBlend(1e-3, 0.01)
    assert blend(Estimate(1.0, 2.0, 3.0)) == Estimate(1.0, 2.0, 3.0)  # before: untouched
    blend.switch()
    first = blend(Estimate(1.1, 0.0, 0.0))  # a fresh observer: v = xi = 0
    assert (first.velocity, first.disturbance) == (2.0, 3.0)  # no jump
    for n in range(1, 50):
        e = blend(Estimate(1.1, 0.5, -1.0))
        r = math.exp(-1e-3 / 0.01) ** n
        assert e.velocity == pytest.approx(0.5 + (2.0 - 0.0) * r, rel=1e-12)
        assert e.disturbance == pytest.approx(-1.0 + (3.0 - 0.0) * r, rel=1e-12)


def test_a_switch_before_any_estimate_changes_nothing() -> None:
    blend = EstimateBlend(1e-3, 0.01)
    blend.switch()
    assert blend(Estimate(0.0, 1.0, 2.0)) == Estimate(0.0, 1.0, 2.0)
