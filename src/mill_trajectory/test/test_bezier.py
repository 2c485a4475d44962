"""Chávez-Conde 8th-order Bézier rest-to-rest move: ends, monotonicity, exact derivatives."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mill_common.parameters import validate_all
from mill_trajectory.bezier import PSI, BezierParams, BezierRestToRest, blend
from numpy.polynomial import polynomial as npoly


def test_blend_polynomial_ends() -> None:
    assert npoly.polyval(1.0, PSI) == 1  # the printed r sum to 1 (exact integers)
    d = np.array(PSI, dtype=float)
    for order in range(1, 10):
        d = npoly.polyder(d)
        at0, at1 = npoly.polyval(0.0, d), npoly.polyval(1.0, d)
        # Derivatives 1…7 vanish at Δ = 0, 1…8 at Δ = 1 (exact in floating point: integers).
        assert (at0 == 0.0) == (order <= 7), order
        assert (at1 == 0.0) == (order <= 8), order


def test_blend_is_the_printed_polynomial() -> None:
    d1 = npoly.polyder(np.array(PSI, dtype=float))
    d2 = npoly.polyder(d1)
    for x in np.linspace(0.01, 0.99, 99):
        psi, dpsi, ddpsi = blend(float(x))
        assert psi == pytest.approx(npoly.polyval(x, PSI), rel=1e-9, abs=1e-12)
        assert dpsi == pytest.approx(npoly.polyval(x, d1), rel=1e-7, abs=1e-9)
        assert ddpsi == pytest.approx(npoly.polyval(x, d2), rel=1e-7, abs=1e-7)
    assert blend(0.5)[0] == pytest.approx(0.5 + math.comb(16, 8) / 2**17)


def test_paper_defaults_and_boundary_values() -> None:
    values = validate_all(BezierRestToRest.PARAMETERS, {})
    path = BezierRestToRest.from_parameters(values)
    assert path.end_time == 3.0
    for t in (-1.0, 0.0):
        s = path.sample(t)
        assert s.position == (0.0, 0.0, 0.0)
        assert s.velocity == s.acceleration == (0.0, 0.0, 0.0)
    for t in (3.0, 10.0):
        s = path.sample(t)
        assert s.position == pytest.approx((0.01, 0.0, 0.0), abs=1e-15)
        assert s.velocity == s.acceleration == (0.0, 0.0, 0.0)
    # Not symmetric: ψ(1/2) = 0.598 with the printed coefficients.
    assert path.sample(1.5).position[0] == pytest.approx(0.01 * blend(0.5)[0])


def test_monotone_and_smooth_near_the_ends() -> None:
    path = BezierRestToRest(
        BezierParams(start=(0.0, 0.02, -0.01), end=(0.01, -0.01, -0.01), t1=1.0, t2=4.0)
    )
    ts = np.linspace(1.0, 4.0, 3001)
    x = np.array([path.sample(t).position for t in ts])
    assert np.all(np.diff(x[:, 0]) >= 0.0)
    assert np.all(np.diff(x[:, 1]) <= 0.0)
    assert np.all(x[:, 2] == -0.01)
    vel = np.array([path.sample(t).velocity[0] for t in ts[1:-1]])
    assert np.all(vel > 0.0)
    # Velocity and acceleration start like Δ⁷, Δ⁶: tiny just after T1 and just before T2.
    assert path.sample(1.03).acceleration[0] < 1e-8
    assert abs(path.sample(3.97).acceleration[0]) < 1e-8


def test_derivatives_match_finite_differences() -> None:
    path = BezierRestToRest()
    h = 1e-5
    for t in np.linspace(0.05, 2.95, 59):
        p0, p1 = path.sample(t - h), path.sample(t + h)
        s = path.sample(t)
        vel_fd = (p1.position[0] - p0.position[0]) / (2 * h)
        acc_fd = (p1.velocity[0] - p0.velocity[0]) / (2 * h)
        assert s.velocity[0] == pytest.approx(vel_fd, rel=1e-6, abs=1e-12)
        assert s.acceleration[0] == pytest.approx(acc_fd, rel=1e-6, abs=1e-10)
    # Peak speed of 10 mm in 3 s at Δ = 7/15: 0.01·ψ'(7/15)/3.
    peak = max(path.sample(t).velocity[0] for t in np.linspace(0, 3, 3001))
    assert peak == pytest.approx(0.01 * blend(7 / 15)[1] / 3, rel=1e-6)
    assert blend(7 / 15)[1] == pytest.approx(3.2487, abs=1e-4)


def test_bad_values() -> None:
    with pytest.raises(ValueError, match='t2'):
        BezierRestToRest(BezierParams(t1=2.0, t2=2.0))
    with pytest.raises(ValueError, match='3 entries'):
        BezierRestToRest(BezierParams(start=(0.0, 0.0)))
    with pytest.raises(ValueError, match='finite'):
        BezierRestToRest(BezierParams(end=(math.nan, 0.0, 0.0)))
