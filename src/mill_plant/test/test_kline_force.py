"""Kline quasi-static cutting force, Beltrán 2013 eq. (4)."""

from __future__ import annotations

import math

import pytest
from mill_plant.kline_force import KlineCuttingForce, KlineParams

FEED = 0.003  # [m/s], the paper's feed rate
INSIDE = (-0.05, -0.06, -0.005)  # 5 mm below the default top, inside the default box
REV = 60.0 / 1800.0  # one spindle revolution [s]


def _k(kline: KlineCuttingForce, speed: float, depth: float) -> float:
    """u_s d_a f, the common factor of eq. (4)."""
    return kline.specific_energy * depth * speed * 60.0 / (kline.teeth * kline.spindle_speed_rpm)


def _force(kline: KlineCuttingForce, t: float, position, velocity) -> tuple[float, ...]:
    """Eq. (4) for a tool fed steadily at `velocity`: chip = velocity * T_z, d_a from z."""
    tz = kline.tooth_period
    feed = (velocity[0] * tz, velocity[1] * tz)
    return kline.chip_force(t, position, feed, kline.workpiece_top - position[2])


def _samples(kline: KlineCuttingForce, velocity: tuple[float, float, float], n: int = 4000):
    t0 = 0.3
    return [_force(kline, t0 + (j + 0.5) * REV / n, INSIDE, velocity) for j in range(n)]


def _mean(forces, i: int) -> float:
    return sum(f[i] for f in forces) / len(forces)


def test_paper_feed_per_tooth() -> None:
    kline = KlineCuttingForce()
    assert kline.feed_per_tooth(FEED) == pytest.approx(0.05e-3, rel=1e-12)
    assert kline.exit_angle == pytest.approx(math.pi, rel=1e-15)  # slotting, b = D


def test_zero_force_at_rest_outside_and_above() -> None:
    kline = KlineCuttingForce()
    t = 0.0123
    assert _force(kline, t, INSIDE, (0.0, 0.0, 0.0)) == (0.0, 0.0, 0.0)
    assert _force(kline, t, INSIDE, (0.0, 0.0, -0.001)) == (0.0, 0.0, 0.0)  # plunging only
    assert _force(kline, t, (-0.2, -0.06, -0.005), (0.0, FEED, 0.0)) == (0.0, 0.0, 0.0)
    assert _force(kline, t, (-0.05, 0.01, -0.005), (0.0, FEED, 0.0)) == (0.0, 0.0, 0.0)
    assert _force(kline, t, (-0.05, -0.06, 0.001), (0.0, FEED, 0.0)) == (0.0, 0.0, 0.0)
    assert _force(kline, t, (-0.05, -0.06, 0.0), (0.0, FEED, 0.0)) == (0.0, 0.0, 0.0)
    # ...while the same instant inside the workpiece does cut.
    assert _force(kline, t, INSIDE, (0.0, FEED, 0.0)) != (0.0, 0.0, 0.0)


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
        fy_feed = _force(kline, t, INSIDE, (0.0, FEED, 0.0))
        fx_feed = _force(kline, t, INSIDE, (FEED, 0.0, 0.0))
        # local y (feed) -> +x, local x -> n = (d_y, -d_x) = -y
        assert fx_feed[0] == pytest.approx(fy_feed[1], rel=1e-12, abs=1e-12)
        assert fx_feed[1] == pytest.approx(-fy_feed[0], rel=1e-12, abs=1e-12)
        assert fx_feed[2] == pytest.approx(fy_feed[2], rel=1e-12, abs=1e-12)
        # Feeding backwards flips the in-plane force: it still resists the motion.
        back = _force(kline, t, INSIDE, (0.0, -FEED, 0.0))
        assert back[0] == pytest.approx(-fy_feed[0], rel=1e-12, abs=1e-12)
        assert back[1] == pytest.approx(-fy_feed[1], rel=1e-12, abs=1e-12)
        # Any feed direction: same in-plane magnitude (a proper rotation).
        c = FEED / math.sqrt(2.0)
        diag = _force(kline, t, INSIDE, (c, -c, 0.0))
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
        base = _force(kline, t, INSIDE, (0.001, 0.002, 0.0))
        fast = _force(kline, t, INSIDE, (0.003, 0.006, 0.0))
        deep = _force(kline, t, (INSIDE[0], INSIDE[1], 2.0 * INSIDE[2]), (0.001, 0.002, 0.0))
        for i in range(3):
            assert fast[i] == pytest.approx(3.0 * base[i], rel=1e-12, abs=1e-12)
            assert deep[i] == pytest.approx(2.0 * base[i], rel=1e-12, abs=1e-12)


def test_engagement_window_half_immersion() -> None:
    # b = D/2: v_m = acos(0) = pi/2; a tooth cuts only while its angle is in (0, pi/2).
    kline = KlineCuttingForce(KlineParams(radial_depth=0.005))
    assert kline.exit_angle == pytest.approx(0.5 * math.pi)
    omega = 2.0 * math.pi * 1800.0 / 60.0
    out = _force(kline, 0.75 * math.pi / omega, INSIDE, (0.0, FEED, 0.0))  # teeth at 3pi/4, 7pi/4
    assert out == (0.0, 0.0, 0.0)
    inside = _force(kline, 0.25 * math.pi / omega, INSIDE, (0.0, FEED, 0.0))  # tooth 0 at pi/4
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
        ({'spindle_speed': -1.0}, 'spindle_speed'),
        ({'specific_energy': math.nan}, 'specific_energy'),
        ({'helix_angle': 114.6}, 'helix_angle'),  # degrees: 2 rad
        ({'workpiece_min': (0.1, -0.1), 'workpiece_max': (0.0, 0.0)}, 'workpiece_min'),
    ],
)
def test_invalid_parameters_are_refused(kwargs: dict, field: str) -> None:
    with pytest.raises(ValueError, match=field):
        KlineCuttingForce(KlineParams(**kwargs))


# --- whose path sets the chip and the depth ----------------------------------------------

TZ = 60.0 / (2 * 1800.0)  # tooth period of the paper's cutter [s]


def test_programmed_chip_is_the_programmed_path_between_tooth_passes() -> None:
    kline = KlineCuttingForce(KlineParams(chip='programmed', depth='programmed'))
    assert kline.tooth_period == pytest.approx(TZ, rel=1e-15)
    # On the first cut (+y at 3 mm/s from t = 0), whatever the tool does: f = 0.05 mm along +y
    # and d_a = 5 mm (the program's z = -5 mm below the top at 0).
    tool = (-0.074, -0.06, -0.0123)  # off the program, deeper than programmed
    for t in (0.5, 3.21, 20.0):
        for velocity in ((0.0, 0.0, 0.0), (0.01, -0.02, 0.003)):
            got = kline.force(t, tool, velocity)
            want = kline.chip_force(t, tool, (0.0, FEED * TZ), 0.005)
            assert got == pytest.approx(want, rel=1e-9, abs=1e-9)
    # Right after the corner (t = 80 mm / 3 mm/s) the chip turns: the programmed path since
    # the previous tooth has a +y part before the corner and a +x part after it.
    corner = 0.08 / FEED
    t = corner + 0.25 * TZ
    got = kline.force(t, tool, (0.0, 0.0, 0.0))
    want = kline.chip_force(t, tool, (0.25 * TZ * FEED, 0.75 * TZ * FEED), 0.005)
    assert got == pytest.approx(want, rel=1e-9, abs=1e-9)
    # At rest (before the start) there is no chip.
    assert kline.force(-0.1, tool, (0.0, 0.0, 0.0)) == (0.0, 0.0, 0.0)
    assert kline.force(60.0, tool, (0.0, 0.0, 0.0)) == (0.0, 0.0, 0.0)


def test_tool_chip_follows_the_path_not_the_velocity_ripple() -> None:
    # The tool feeds +y at 3 mm/s with a 60 Hz velocity ripple of 2 mm/s amplitude (what the
    # observer's loop shows under cutting). The ripple has the tooth period, so the path since
    # the previous tooth is exactly the programmed 0.05 mm, while |v| ranges 1 .. 5 mm/s.
    kline = KlineCuttingForce()
    w = 2.0 * math.pi * 60.0
    amp = 0.002 / w
    h = 0.25e-3  # the plant's RK4 substep at 1 kHz with 4 substeps

    def state(t: float):
        y = INSIDE[1] + FEED * t + amp * math.sin(w * t)
        return (INSIDE[0], y, INSIDE[2]), (0.0, FEED + 0.002 * math.cos(w * t), 0.0)

    worst = 0.0
    for k in range(400):
        t = k * h
        kline.commit(t, *state(t))
        if t < 2 * TZ:
            continue
        for tau in (t, t + 0.5 * h, t + h):  # the RK4 stages ask ahead of the last commit
            position, velocity = state(tau)
            got = kline.force(tau, position, velocity)
            want = kline.chip_force(tau, position, (0.0, FEED * TZ), 0.005)
            worst = max(worst, max(abs(g - v) for g, v in zip(got, want, strict=True)))
    # Numerics: the cubic Hermite interpolation of the past position errs by at most
    # h^4 max|y^(4)| / 384 = (2.5e-4 s)^4 * (0.002 m/s * w^3 = 1.07e5 m/s^4) / 384 = 1.1e-12 m,
    # and eq. (4) turns a chip error into at most u_s d_a * 1.03 = 7.0e6 N/m: 7.7e-6 N. The
    # old model (f from |v|) was off by up to 230 N here.
    assert worst < 7.7e-6


def test_tool_chip_is_zero_for_a_tool_that_stood_for_a_tooth_period() -> None:
    kline = KlineCuttingForce()
    kline.commit(0.0, INSIDE, (0.0, 0.0, 0.0))
    assert kline.force(0.5, INSIDE, (0.0, FEED, 0.0)) == (0.0, 0.0, 0.0)
    kline.commit(0.6, INSIDE, (0.0, 0.0, 0.0))
    # Moved 0.01 mm in +x since the previous tooth: a chip of 0.01 mm along +x.
    moved = (INSIDE[0] + 1e-5, INSIDE[1], INSIDE[2])
    got = kline.force(0.6, moved, (0.0, 0.0, 0.0))
    assert got == pytest.approx(kline.chip_force(0.6, moved, (1e-5, 0.0), 0.005), rel=1e-12)


def test_commit_keeps_time_order_and_force_needs_a_committed_path() -> None:
    kline = KlineCuttingForce()
    with pytest.raises(ValueError, match='commit first'):
        kline.force(0.1, INSIDE, (0.0, FEED, 0.0))
    kline.commit(1.0, INSIDE, (0.0, 0.0, 0.0))
    kline.commit(1.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))  # the same instant: replaced
    assert kline.past_position(0.0) == (0.0, 0.0)
    with pytest.raises(ValueError, match='backwards'):
        kline.commit(0.999, INSIDE, (0.0, 0.0, 0.0))


def test_past_position_is_exact_on_a_cubic_path() -> None:
    kline = KlineCuttingForce()
    for k in range(200):
        t = k * 1e-3
        kline.commit(t, (t**3, 2.0 * t, 0.0), (3.0 * t * t, 2.0, 0.0))
    for tau in (0.1705, 0.18, 0.19833):  # within the 2 T_z of the past that is kept
        x, y = kline.past_position(tau)
        assert x == pytest.approx(tau**3, rel=1e-12)
        assert y == pytest.approx(2.0 * tau, rel=1e-12)


def test_programmed_depth_ignores_the_tool_z_and_tool_depth_follows_it() -> None:
    fixed = KlineCuttingForce(KlineParams(chip='programmed', depth='programmed'))
    coupled = KlineCuttingForce(KlineParams(chip='programmed', depth='tool'))
    t = 2.0 + 0.3 * TZ
    shallow, deep = (-0.075, -0.099, -0.005), (-0.075, -0.099, -0.010)
    assert fixed.force(t, deep, (0, 0, 0)) == fixed.force(t, shallow, (0, 0, 0))
    pairs = zip(
        coupled.force(t, deep, (0, 0, 0)), coupled.force(t, shallow, (0, 0, 0)), strict=True
    )
    for a, b in pairs:
        assert a == pytest.approx(2.0 * b, rel=1e-12)
    # Above the top no tool cuts, whatever the program says.
    assert fixed.force(t, (-0.075, -0.099, 0.001), (0, 0, 0)) == (0.0, 0.0, 0.0)


@pytest.mark.parametrize(
    ('kwargs', 'field'),
    [
        ({'chip': 'velocity'}, 'chip'),
        ({'depth': 'fixed'}, 'depth'),
        ({'program': [0.0, 0.0, 0.0]}, 'program'),
        ({'program': [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]}, 'program'),
        ({'program_feed_rate': 0.0}, 'program_feed_rate'),
    ],
)
def test_invalid_path_parameters_are_refused(kwargs: dict, field: str) -> None:
    with pytest.raises(ValueError, match=field):
        KlineCuttingForce(KlineParams(**kwargs))


def test_only_the_tools_chip_reads_the_tools_path() -> None:
    """The programmed chip is not path-dependent, so a plant does not commit its states to it;
    its force, inside and outside the workpiece box, is the one the tool's path would not change."""
    from mill_plant.axis_plant import AxisPlant
    from mill_plant.models.rigid import RigidAxisModel

    assert KlineCuttingForce(KlineParams(chip='tool')).PATH_DEPENDENT
    programmed = KlineCuttingForce(KlineParams(chip='programmed', depth='programmed'))
    assert not programmed.PATH_DEPENDENT
    assert KlineCuttingForce.PATH_DEPENDENT  # the class: a model that may read it
    rigid = [RigidAxisModel.from_parameters(i, {}) for i in range(3)]
    plant = AxisPlant(rigid, programmed, initial_position=(-0.075, -0.105, -0.005))
    for _ in range(40):
        plant.step((0.1, 0.1, 0.0), 0.001)
    assert programmed._t == []  # nothing committed
    inside = programmed.force(0.04, (-0.075, -0.105, -0.005), (0.0, 0.0, 0.0))
    assert inside[1] > 0.0  # cutting, 40 ms into the programmed +y feed
    assert programmed.force(0.04, (-0.075, -0.105, 0.001), (0.0, 0.0, 0.0)) == (0.0, 0.0, 0.0)
    assert programmed.force(0.04, (0.031, -0.105, -0.005), (0.0, 0.0, 0.0)) == (0.0, 0.0, 0.0)
