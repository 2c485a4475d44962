"""The reference at a stamp: exact on the grid, interpolated between points."""

from __future__ import annotations

import pytest
from mill_common.reference_buffer import ReferenceBuffer
from mill_common.signals import AxisReference


def test_exact_on_points_interpolated_between_none_outside() -> None:
    buf = ReferenceBuffer()
    buf.add(2000, AxisReference(0.3, 3.0, 30.0))
    buf.add(1000, AxisReference(0.1, 1.0, 10.0))
    p = AxisReference(0.1 + 1e-17, 1.0, 10.0)
    buf.add(1000, p)  # a newer message's point replaces the old one
    assert buf.at(1000) is p
    mid = buf.at(1500)
    assert mid is not None
    assert mid.position == pytest.approx(0.2) and mid.velocity == pytest.approx(2.0)
    assert mid.acceleration == pytest.approx(20.0)
    assert buf.at(999) is None and buf.at(2001) is None
    assert buf.newest == 2000 and len(buf) == 2


def test_forget_keeps_the_point_before() -> None:
    buf = ReferenceBuffer()
    for k in range(10):
        buf.add(k * 100, AxisReference(float(k), 0.0, 0.0))
    buf.forget_before(550)
    assert buf.at(500) is not None and buf.at(550) is not None
    assert buf.at(400) is None
    assert len(buf) == 5
