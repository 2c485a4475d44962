"""Command shaping: the notch and low-pass where they are asked for, the friction
feed-forward on the Stribeck curve, LinuxCNC's backlash offset; off by default."""

from __future__ import annotations

import cmath
import math

import pytest
from mill_common.parameters import ParameterError
from mill_controllers.command_shaping import (
    BacklashParams,
    Biquad,
    CommandFilterParams,
    CommandShaping,
    FrictionCompensationParams,
    command_filters,
)
from mill_controllers.config import build_loop, parameter_specs

T = 0.001


def gain(f: Biquad, hz: float) -> float:
    z = cmath.exp(2j * math.pi * hz * T)
    num = f.b0 + f.b1 / z + f.b2 / z**2
    return abs(num / (1.0 + f.a1 / z + f.a2 / z**2))


def test_the_notch_takes_out_its_frequency_and_leaves_the_others() -> None:
    (notch,) = command_filters(CommandFilterParams(notch_frequency=70.0, notch_damping=0.3), T)
    assert gain(notch, 70.0) < 1e-9  # pre-warped: exactly at 70 Hz, not at 68
    assert gain(notch, 68.0) > 0.05
    assert gain(notch, 5.0) == pytest.approx(1.0, abs=0.01)
    assert gain(notch, 400.0) == pytest.approx(1.0, abs=0.02)
    half = command_filters(CommandFilterParams(notch_frequency=70.0, notch_depth=0.5), T)[0]
    assert gain(half, 70.0) == pytest.approx(0.5, rel=1e-6)


def test_the_lowpass_is_3_db_down_at_its_corner() -> None:
    (lp,) = command_filters(CommandFilterParams(lowpass_frequency=100.0), T)
    assert gain(lp, 100.0) == pytest.approx(1.0 / math.sqrt(2.0), rel=1e-3)
    assert gain(lp, 1.0) == pytest.approx(1.0, abs=1e-4)
    # stepped: a unit step settles at 1
    out = [lp.step(1.0) for _ in range(200)]
    assert out[-1] == pytest.approx(1.0, abs=1e-6)


def test_a_filter_at_or_above_nyquist_is_refused() -> None:
    with pytest.raises(ParameterError, match=r'command_filter\.notch_frequency'):
        command_filters(CommandFilterParams(notch_frequency=500.0), T)


def test_the_friction_feed_forward_follows_the_stribeck_curve() -> None:
    p = FrictionCompensationParams(
        breakaway=0.6, sliding=0.35, stribeck_speed=0.002, viscous=2.0, smoothing_speed=1e-4
    )
    assert p.torque(0.0) == 0.0  # smoothed through zero speed: no step at a reversal
    assert p.torque(5e-4) == pytest.approx(
        math.tanh(5.0) * (0.35 + 0.25 * math.exp(-(0.25**2))) + 1e-3, rel=1e-9
    )
    assert p.torque(-0.02) == pytest.approx(-(0.35 + 0.25 * math.exp(-100.0)) - 0.04, rel=1e-9)
    with pytest.raises(ParameterError, match=r'friction_compensation\.breakaway'):
        FrictionCompensationParams(breakaway=0.2, sliding=0.35)


def test_the_backlash_offset_is_half_the_gap_towards_the_motion_ramped() -> None:
    s = CommandShaping(T, backlash=BacklashParams(width=16e-6, ramp_time=0.01))
    ups = [s.offset(0.003) for _ in range(20)]
    assert ups[0] == pytest.approx(0.5 * 16e-6 * 0.2)  # 1 ms of a 10 ms ramp from 0 to 1
    assert ups[-1] == pytest.approx(8e-6)
    downs = [s.offset(-0.003) for _ in range(20)]
    assert downs[4] == pytest.approx(0.0, abs=1e-12)  # half way: 5 ms of the 10 ms ramp
    assert downs[-1] == pytest.approx(-8e-6)
    assert s.offset(0.0) == pytest.approx(-8e-6)  # at rest: it stays on its side


def test_all_of_it_is_off_by_default_and_declared_on_the_controller_node() -> None:
    assert not CommandShaping(T).active
    names = [n for n, _ in parameter_specs()]
    for name in (
        'command_filter.notch_frequency',
        'command_filter.lowpass_frequency',
        'friction_compensation.breakaway',
        'friction_compensation.smoothing_speed',
        'backlash.width',
    ):
        assert name in names
    values = {n: s.default for n, s in parameter_specs()}
    values.update(axis='x', sample_period=T, input_gain=20.0)
    assert build_loop(values).shaping is None
