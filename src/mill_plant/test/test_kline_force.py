"""Kline quasi-static cutting force, Beltrán 2013 eq. (4)."""

from __future__ import annotations

import math

import pytest
from mill_plant.kline_force import KlineCuttingForce

FEED = 0.003  # [m/s], the paper's feed rate
INSIDE = (-0.05, -0.06, -0.005)  # 5 mm below the default top, inside the default box
REV = 60.0 / 1800.0  # one spindle revolution [s]


def _k(kline: KlineCuttingForce, speed: float, depth: float) -> float:
    """u_s d_a f, the common factor of eq. (4)."""
    return kline.specific_energy * depth * speed * 60.0 / (kline.teeth * kline.spindle_speed_rpm)


def _samples(kline: KlineCuttingForce, velocity: tuple[float, float, float], n: int = 4000):
    t0 = 0.3
    return [kline.force(t0 + (j + 0.5) * REV / n, INSIDE, velocity) for j in range(n)]


def _mean(forces, i: int) -> float:
    return sum(f[i] for f in forces) / len(forces)


def test_paper_feed_per_tooth() -> None:
    kline = KlineCuttingForce()
    assert kline.feed_per_tooth(FEED) == pytest.approx(0.05e-3, rel=1e-12)
    assert kline.exit_angle == pytest.approx(math.pi, rel=1e-15)  # slotting, b = D


def test_zero_force_at_rest_outside_and_above() -> None:
    kline = KlineCuttingForce()
    t = 0.0123
    assert kline.force(t, INSIDE, (0.0, 0.0, 0.0)) == (0.0, 0.0, 0.0)
    assert kline.force(t, INSIDE, (0.0, 0.0, -0.001)) == (0.0, 0.0, 0.0)  # plunging only
    assert kline.force(t, (-0.2, -0.06, -0.005), (0.0, FEED, 0.0)) == (0.0, 0.0, 0.0)
    assert kline.force(t, (-0.05, 0.01, -0.005), (0.0, FEED, 0.0)) == (0.0, 0.0, 0.0)
    assert kline.force(t, (-0.05, -0.06, 0.001), (0.0, FEED, 0.0)) == (0.0, 0.0, 0.0)
    assert kline.force(t, (-0.05, -0.06, 0.0), (0.0, FEED, 0.0)) == (0.0, 0.0, 0.0)
    # ...while the same instant inside the workpiece does cut.
    assert kline.force(t, INSIDE, (0.0, FEED, 0.0)) != (0.0, 0.0, 0.0)


def test_feed_along_y_means_over_a_revolution() -> None:
    # Slotting with 2 teeth: exactly one tooth in (0, pi) at a time, so over a revolution
    # mean(sum sin^2) = 1/2, mean(sum sin cos) = 0, mean(sum sin) = 2/pi.
    kline = KlineCuttingForce()
    k = _k(kline, FEED, 0.005)
    assert k == pytest.approx(342.5, rel=1e-12)
    forces = _samples(kline, (0.0, FEED, 0.0))
    mean_fy = _mean(forces, 1)
    assert mean_fy > 0.0  # resists the +y feed under eq. (1)
    assert mean_fy == pytest.approx(0.5 * k, rel=1e-9)
    assert _mean(forces, 0) == pytest.approx(0.3 * mean_fy, rel=1e-9)
    assert _mean(forces, 2) == pytest.approx(
        0.3 * math.tan(math.radians(45.0)) * k * 2.0 / math.pi, rel=1e-6
    )


def test_peak_forces() -> None:
    kline = KlineCuttingForce()
    k = _k(kline, FEED, 0.005)
    forces = _samples(kline, (0.0, FEED, 0.0), n=20000)
    # max of sin^2 v - 0.3 sin v cos v = 0.5 + sqrt(0.25 + 0.15^2), etc.
    root = math.sqrt(0.25 + 0.15**2)
    assert max(f[1] for f in forces) == pytest.approx(k * (0.5 + root), rel=1e-6)
    assert max(f[0] for f in forces) == pytest.approx(k * (0.15 + root), rel=1e-6)
    assert min(f[0] for f in forces) == pytest.approx(k * (0.15 - root), rel=1e-5)
    assert max(f[2] for f in forces) == pytest.approx(0.3 * k, rel=1e-6)
    assert min(f[2] for f in forces) >= 0.0


def test_feed_along_x_is_the_same_force_rotated() -> None:
    kline = KlineCuttingForce()
    for j in range(200):
        t = 0.01 + j * 1.7e-4
        fy_feed = kline.force(t, INSIDE, (0.0, FEED, 0.0))
        fx_feed = kline.force(t, INSIDE, (FEED, 0.0, 0.0))
        # local y (feed) -> +x, local x -> n = (d_y, -d_x) = -y
        assert fx_feed[0] == pytest.approx(fy_feed[1], rel=1e-12, abs=1e-12)
        assert fx_feed[1] == pytest.approx(-fy_feed[0], rel=1e-12, abs=1e-12)
        assert fx_feed[2] == pytest.approx(fy_feed[2], rel=1e-12, abs=1e-12)
        # Feeding backwards flips the in-plane force: it still resists the motion.
        back = kline.force(t, INSIDE, (0.0, -FEED, 0.0))
        assert back[0] == pytest.approx(-fy_feed[0], rel=1e-12, abs=1e-12)
        assert back[1] == pytest.approx(-fy_feed[1], rel=1e-12, abs=1e-12)
        # Any feed direction: same in-plane magnitude (a proper rotation).
        c = FEED / math.sqrt(2.0)
        diag = kline.force(t, INSIDE, (c, -c, 0.0))
        assert math.hypot(diag[0], diag[1]) == pytest.approx(
            math.hypot(fy_feed[0], fy_feed[1]), rel=1e-9, abs=1e-9
        )
    means = _samples(kline, (FEED, 0.0, 0.0))
    assert _mean(means, 0) == pytest.approx(0.5 * _k(kline, FEED, 0.005), rel=1e-9)
    assert _mean(means, 1) == pytest.approx(-0.15 * _k(kline, FEED, 0.005), rel=1e-9)


def test_force_is_linear_in_feed_velocity_and_depth() -> None:
    kline = KlineCuttingForce()
    for j in range(50):
        t = 0.2 + j * 3.1e-4
        base = kline.force(t, INSIDE, (0.001, 0.002, 0.0))
        fast = kline.force(t, INSIDE, (0.003, 0.006, 0.0))
        deep = kline.force(t, (INSIDE[0], INSIDE[1], 2.0 * INSIDE[2]), (0.001, 0.002, 0.0))
        for i in range(3):
            assert fast[i] == pytest.approx(3.0 * base[i], rel=1e-12, abs=1e-12)
            assert deep[i] == pytest.approx(2.0 * base[i], rel=1e-12, abs=1e-12)


def test_engagement_window_half_immersion() -> None:
    # b = D/2: v_m = acos(0) = pi/2; a tooth cuts only while its angle is in (0, pi/2).
    kline = KlineCuttingForce(radial_depth=0.005)
    assert kline.exit_angle == pytest.approx(0.5 * math.pi)
    omega = 2.0 * math.pi * 1800.0 / 60.0
    out = kline.force(0.75 * math.pi / omega, INSIDE, (0.0, FEED, 0.0))  # teeth at 3pi/4, 7pi/4
    assert out == (0.0, 0.0, 0.0)
    inside = kline.force(0.25 * math.pi / omega, INSIDE, (0.0, FEED, 0.0))  # tooth 0 at pi/4
    k = _k(kline, FEED, 0.005)
    s = math.sin(0.25 * math.pi)
    assert inside[1] == pytest.approx(k * (s * s - 0.3 * s * s), rel=1e-9)
    assert inside[0] == pytest.approx(k * (0.3 * s * s + s * s), rel=1e-9)
    assert inside[2] == pytest.approx(0.3 * k * s, rel=1e-9)


@pytest.mark.parametrize(
    ('kwargs', 'field'),
    [
        ({'radial_depth': 0.02}, 'radial_depth'),
        ({'tool_diameter': 0.0}, 'tool_diameter'),
        ({'teeth': 0}, 'teeth'),
        ({'spindle_speed_rpm': -1.0}, 'spindle_speed_rpm'),
        ({'specific_energy': math.nan}, 'specific_energy'),
        ({'helix_angle': 2.0}, 'helix_angle'),
        ({'workpiece_min': (0.1, -0.1), 'workpiece_max': (0.0, 0.0)}, 'workpiece_min'),
    ],
)
def test_invalid_parameters_are_refused(kwargs: dict, field: str) -> None:
    with pytest.raises(ValueError, match=field):
        KlineCuttingForce(**kwargs)
