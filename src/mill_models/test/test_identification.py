"""The identification of a rigid axis (mill_models.identification) on records made here.

The records come from a small simulation of the model itself (held command, delay, Coulomb
friction with sticking, a constant load, an encoder), under a PD hold and a random binary
torque as the identify job applies them; the parameters it was made with are what the fit
must find. Bad records must give one clear IdentificationError and no model.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from mill_models.identification import (
    FitSettings,
    IdentificationError,
    identify_axis,
    predict_window,
    split_windows,
)

T = 0.001
SHORT = 0.15 * 10 / (0.15 * 10 + 0.85)  # a new bit's chance to be short (excitation.py)


def record(
    b: float = 16.0,
    alpha: float = 0.08,
    beta: float = 0.5,
    gamma: float = 0.0,
    delay: int = 1,
    seconds: float = 20.0,
    amplitude: float = 1.0,
    resolution: float = 1e-6,
    sign: float = 1.0,
    seed: int = 3,
    T: float = T,
    sine: float = 0.002,
) -> tuple[np.ndarray, np.ndarray]:
    """Positions and commands of an axis moved by a PD hold and a binary torque."""
    rng = np.random.default_rng(seed)
    kinds = np.random.default_rng([seed, 1])  # short or long: a stream of its own
    n = round(seconds / T)
    sub = 20
    h = T / sub
    x = v = 0.0
    pending = [0.0] * delay
    xs, us = np.empty(n), np.empty(n)
    bit, left = 1.0, 0
    w = 30.0
    xi_hat = 0.0
    for k in range(n):
        y = round(x / resolution) * resolution if resolution else x
        if left == 0:
            # bits of 1-4 × 10 samples, and 15 % of the time 1-4 samples (the job's law)
            bit = 1.0 if rng.random() < 0.5 else -1.0
            length = int(rng.integers(1, 5))
            left = length * (1 if kinds.random() < SHORT else 10)
        left -= 1
        ref = sine * math.sin(2 * math.pi * 0.5 * k * T)
        # a PD hold (with the load it is told) plus the binary torque
        u = (-(w * w) * (y - ref) - 2 * w * v + gamma - xi_hat) / b + bit * amplitude / b
        xs[k], us[k] = y, u
        pending.append(u)
        acting = sign * pending.pop(0)
        for _ in range(sub):
            drive = b * acting - gamma
            if v == 0.0 and abs(drive) <= beta:
                continue  # stuck
            s = math.copysign(1.0, v) if v != 0.0 else math.copysign(1.0, drive)
            a = drive - alpha * v - beta * s
            v_new = v + h * a
            if v != 0.0 and v_new * v < 0.0:
                v_new = 0.0  # stops at the reversal; friction decides what follows
            x += h * 0.5 * (v + v_new)
            v = v_new
    return xs, us


@pytest.mark.parametrize('delay', [0, 1, 3])
def test_the_fit_finds_the_parameters_and_the_delay_it_was_made_with(delay: int) -> None:
    x, u = record(delay=delay, gamma=2.5)
    m = identify_axis(x, u, T)
    assert m.delay == delay
    assert m.b.value == pytest.approx(16.0, rel=0.02)
    assert m.alpha.value == pytest.approx(0.08, rel=0.10)
    assert m.beta.value == pytest.approx(0.5, rel=0.10)
    assert m.gamma.value == pytest.approx(2.5, rel=0.02)
    assert m.b.half_width < 0.02 * m.b.value
    # the encoder's quantization is what is left: 1 µm / √12
    assert m.fit_rms < 0.5e-6 and m.validation_rms < 0.5e-6


def test_the_torque_terms_are_the_balancing_motor_torques() -> None:
    x, u = record(gamma=2.5)
    m = identify_axis(x, u, T)
    assert m.torque('gamma').value == pytest.approx(2.5 / 16.0, rel=0.02)
    assert m.torque('beta').value == pytest.approx(0.5 / 16.0, rel=0.10)


def test_the_held_out_windows_come_after_the_fitted_ones_and_are_predicted() -> None:
    x, u = record()
    fit, held = split_windows(x, T, FitSettings())
    assert held and min(w.start for w in held) >= max(w.stop for w in fit)
    m = identify_axis(x, u, T)
    t, measured, predicted = predict_window(m, x, u, held[0])
    assert len(t) == len(measured) == len(predicted)
    assert np.sqrt(np.mean((measured - predicted) ** 2)) < 1e-6


def test_an_axis_that_does_not_move_is_refused() -> None:
    x, u = record(amplitude=0.0, beta=50.0)  # the hold never overcomes the friction
    with pytest.raises(IdentificationError, match='too little motion'):
        identify_axis(x, u, T)


def test_too_little_excitation_gives_no_fit_from_noise() -> None:
    # plenty of motion from the hold's sine, but almost no binary torque and a coarse
    # encoder: the record cannot tell the delay (nor pin b), and says so
    x, u = record(amplitude=0.02, sine=0.01, resolution=20e-6)
    with pytest.raises(IdentificationError, match='too little excitation'):
        identify_axis(x, u, T)


def test_a_drive_that_pushes_against_its_command_is_refused() -> None:
    x, u = record()
    with pytest.raises(IdentificationError, match='accelerates against its command'):
        identify_axis(x, -u, T)


def test_an_unstable_model_is_refused() -> None:
    x, u = record(alpha=-0.5, seconds=20.0)  # negative damping: something else drives it
    with pytest.raises(IdentificationError, match='negative'):
        identify_axis(x, u, T)


def test_a_record_with_gaps_or_unequal_series_is_refused() -> None:
    x, u = record(seconds=2.0)
    x[10] = math.nan
    with pytest.raises(IdentificationError, match='non-finite'):
        identify_axis(x, u, T)
    with pytest.raises(IdentificationError, match='equal length'):
        identify_axis(x[:-1], u, T)


def test_a_slower_rate_is_identified_too() -> None:
    x, u = record(T=0.004, seconds=30.0, gamma=2.5)
    m = identify_axis(x, u, 0.004)
    assert m.delay == 1
    assert m.b.value == pytest.approx(16.0, rel=0.02)
    assert m.alpha.value == pytest.approx(0.08, rel=0.10)
    assert m.beta.value == pytest.approx(0.5, rel=0.10)
