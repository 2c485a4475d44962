"""β-FROH, Rubio 2013 eq. (4)-(6): ZOH limit, eq. (6) identity, poles, the reconstruction, the
feed clamp, the held plant; and the sample hold."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.signal
from mill_models.force_process import ForceProcessModel, ForceProcessParams, ForceProcessPlant
from mill_models.holds import (
    HeldPlant,
    SampleHold,
    as_state_space,
    clamped_pieces,
    froh_discretize,
    hold_input,
)
from mill_models.quadrature import simpson
from mill_models.reference_model import ContinuousReference, natural_frequency

MODEL = ForceProcessModel()
T = MODEL.sample_period
PLANT_S = MODEL.unit_transfer_function()
SYSTEMS = {
    'force process': PLANT_S,
    'with a zero': (np.array([0.5, 3.0]), np.array([1.0, 7.0, 30.0, 20.0])),
    'reference model': (np.array([98.6]), np.array([1.0, 13.9, 98.6])),
}


@pytest.mark.parametrize('name', list(SYSTEMS))
def test_beta_zero_is_scipy_zoh(name: str) -> None:
    num, den = SYSTEMS[name]
    got = froh_discretize((num, den), T, 0.0)
    numd, dend, _ = scipy.signal.cont2discrete((num, den), T, method='zoh')
    numd = np.ravel(numd)
    np.testing.assert_allclose(got.den, dend, rtol=0, atol=1e-12)
    np.testing.assert_allclose(
        got.num, np.concatenate([np.zeros(len(dend) - len(numd)), numd]), rtol=0, atol=1e-12
    )


def test_state_space_input_gives_the_same_model() -> None:
    a, b, c, d = as_state_space(PLANT_S)
    for beta in (-0.6, 0.0, 0.8):
        h1 = froh_discretize(PLANT_S, T, beta)
        h2 = froh_discretize((a, b, c, d), T, beta)
        np.testing.assert_allclose(h1.num, h2.num, atol=1e-13)
        np.testing.assert_allclose(h1.den, h2.den, atol=1e-13)


def _zoh_eval(num, den, z: complex) -> complex:
    nd, dd, _ = scipy.signal.cont2discrete((num, den), T, method='zoh')
    return np.polyval(np.ravel(nd), z) / np.polyval(dd, z)


@pytest.mark.parametrize('name', list(SYSTEMS))
@pytest.mark.parametrize('beta', [-1.0, -0.3, 0.4, 1.0])
def test_matches_eq6_written_with_zero_order_holds(name: str, beta: float) -> None:
    num, den = SYSTEMS[name]
    h = froh_discretize((num, den), T, beta)
    den_s = np.polymul(den, [1.0, 0.0])  # G(s)/s
    for w in (0.3, 2.0, 9.0, 25.0):
        z = np.exp(1j * w * T)
        # Rubio 2013 eq. (6): H_β = (z−β)/z·Z[h_o G] + β(z−1)/(Tz)·Z[h_o G/s]
        expected = (z - beta) / z * _zoh_eval(num, den, z) + beta * (z - 1) / (T * z) * _zoh_eval(
            num, den_s, z
        )
        got = np.polyval(h.num, z) / np.polyval(h.den, z)
        assert got == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize('beta', [-1.0, -0.3, 0.25, 1.0])
def test_poles_are_exp_of_minus_t_over_tau_plus_the_origin(beta: float) -> None:
    h = froh_discretize(PLANT_S, T, beta)
    expected = np.sort([0.0, math.exp(-T / MODEL.tau_m), math.exp(-T / MODEL.tau_c)])
    np.testing.assert_allclose(np.sort(h.poles().real), expected, atol=1e-12)
    assert np.all(np.abs(h.poles()) < 1.0)  # e^{−T/τ}, not the misprinted e^{T/τ}
    assert h.order == 3
    assert h.dc_gain() == pytest.approx(1.0, rel=1e-12)
    assert froh_discretize(PLANT_S, T, 0.0).order == 2


@pytest.mark.parametrize('beta', [-1.0, -0.3, 0.0, 0.6, 1.0])
def test_plant_under_the_hold_reproduces_the_discrete_model(beta: float) -> None:
    """The plant integrated with the β-hold reconstruction, sampled, equals H_β(z)."""
    rng = np.random.default_rng(4)
    u = rng.uniform(1.0, 9.0, 25)
    model = ForceProcessModel(ForceProcessParams(depth_profile=[0.0, 2.0]))
    plant = ForceProcessPlant(model)
    y = [plant.force]
    u_prev = 0.0
    for uk in u[:-1]:
        u0, slope = hold_input(uk, u_prev, beta, T)
        y.append(plant.step(u0, slope, T))
        u_prev = uk
    h = froh_discretize(PLANT_S, T, beta)
    expected = model.process_gain(2.0) * scipy.signal.lfilter(h.num, h.den, u)
    np.testing.assert_allclose(y, expected, rtol=1e-10, atol=1e-9)


def test_hold_input_is_the_beta_reconstruction() -> None:
    u0, slope = hold_input(5.0, 3.0, -0.3, 0.1)
    assert u0 == 5.0
    assert u0 + slope * 0.1 == pytest.approx(5.0 - 0.3 * 2.0)
    assert hold_input(5.0, 3.0, 0.0, 0.1) == (5.0, 0.0)


def test_beta_outside_range_is_refused() -> None:
    with pytest.raises(ValueError, match='beta'):
        froh_discretize(PLANT_S, T, 1.5)
    with pytest.raises(ValueError, match='beta'):
        froh_discretize(PLANT_S, T, math.nan)
    with pytest.raises(ValueError, match='period'):
        froh_discretize(PLANT_S, 0.0, 0.0)


@pytest.mark.parametrize(('u0', 'slope'), [(5.0, 200.0), (5.0, -200.0), (25.0, -400.0), (3.0, 0.0)])
def test_clamped_pieces_stay_in_range_and_follow_the_ramp_inside(u0: float, slope: float) -> None:
    lo, hi, dur = 0.0, 12.0, 0.1
    pieces = clamped_pieces(u0, slope, dur, lo, hi)
    assert sum(p[0] for p in pieces) == pytest.approx(dur)
    t = 0.0
    for length, start, sl in pieces:
        for tau in np.linspace(0.0, length, 7):
            value = start + sl * tau
            assert lo - 1e-9 <= value <= hi + 1e-9
            assert value == pytest.approx(min(hi, max(lo, u0 + slope * (t + tau))), abs=1e-9)
        t += length


@pytest.mark.parametrize('beta', [-0.5, 0.0, 1.0])
def test_held_plant_applies_the_clamped_reconstruction(beta: float) -> None:
    """advance() = plant steps over the clamped β-reconstruction; the cost is ∫(F_p − F_pm)²."""
    model = ForceProcessModel(ForceProcessParams(depth_profile=[0.0, 2.0, 0.3, 3.0]))
    lo, hi = 0.0, 8.0
    held = HeldPlant(ForceProcessPlant(model), lo, hi)
    traced = HeldPlant(ForceProcessPlant(model), lo, hi)
    reference = ContinuousReference(0.7, natural_frequency(3.0 * T))
    by_hand = ForceProcessPlant(model)
    u_prev = 0.0
    for uk in (6.0, 12.0, 1.0, -3.0, 5.0):
        force, cost, pieces = held.advance(uk, beta)
        assert cost == 0.0 and pieces == []
        reference.begin(1000.0)
        force2, cost2, pieces2 = traced.advance(uk, beta, reference, keep_trace=True)
        reference.advance(T)
        assert force2 == pytest.approx(force, rel=1e-12)
        assert cost2 == pytest.approx(
            sum(simpson(t, (f - fr) ** 2) for t, f, fr in pieces2), rel=1e-12
        )
        u0, slope = hold_input(uk, u_prev, beta, T)
        for length, start, sl in clamped_pieces(u0, slope, T, lo, hi):
            by_hand.step(start, sl, length)
        assert force == pytest.approx(by_hand.force, rel=1e-12)
        u_prev = uk
    assert held.clamp(-1.0) == lo and held.clamp(9.0) == hi


def test_sample_hold_replaces_non_finite_samples() -> None:
    hold = SampleHold(0.0)
    assert [hold(v) for v in (5.0, math.nan, math.inf, 7.0, -math.inf)] == [5, 5, 5, 7, 7]
    assert hold.held == 3
