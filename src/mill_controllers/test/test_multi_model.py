"""Multi-model schemes 1 and 2 of Rubio 2013 §3.2: switching rules, residence, causality."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mill_common.parameters import ParameterError
from mill_controllers.model_reference import ForceControlParams, ModelReferenceForceController
from mill_controllers.multi_model import PAPER_BETAS, MultiModelScheme1, MultiModelScheme2
from mill_models.force_process import ForceProcessModel, ForceProcessParams, ForceProcessPlant
from mill_models.holds import HeldPlant

MODEL = ForceProcessModel()
LO, HI = 0.0, 20.0


def _run(ctrl, n: int, model: ForceProcessModel = MODEL):
    """Closed loop on the plant; returns (betas, feeds, forces, candidate sets)."""
    held = HeldPlant(ForceProcessPlant(model), LO, HI)
    betas, feeds, forces, cands = [], [], [], []
    for _ in range(n):
        y = held.plant.force
        ctrl.set_depth(model.depth_at(held.plant.time))
        u = min(HI, max(LO, ctrl.update(1200.0, y)))
        ctrl.record_applied(u)
        held.advance(u, ctrl.active_beta)
        betas.append(ctrl.active_beta)
        feeds.append(u)
        forces.append(y)
        cands.append(list(getattr(ctrl, 'candidate_betas', [])))
    return np.array(betas), np.array(feeds), np.array(forces), cands


def test_paper_beta_set() -> None:
    assert PAPER_BETAS == (1.0, 0.75, 0.5, 0.25, 0.0, -0.25, -0.5, -0.75, -1.0)


def test_scheme1_respects_set_residence_time_and_freeze() -> None:
    ctrl = MultiModelScheme1.from_parameters(MODEL, {'stop_after': 60}, LO, HI)
    betas, _, _, _ = _run(ctrl, 100)
    assert set(betas) <= set(PAPER_BETAS)
    switches = np.nonzero(np.diff(betas))[0] + 1  # first sample with the new β
    assert len(switches) >= 1  # the depth changes at 2 s and 4 s make it switch
    assert np.all(np.diff(switches) >= 2)  # τ_R = 2 T
    assert np.all(switches < 60)  # frozen from sample 60 on
    assert ctrl.frozen
    assert ctrl.switch_count == len(switches)


def test_scheme1_with_one_candidate_is_the_fixed_controller() -> None:
    mm = MultiModelScheme1.from_parameters(MODEL, {'betas': [-0.3], 'initial_beta': -0.3}, LO, HI)
    fixed = ModelReferenceForceController(MODEL, ForceControlParams(beta=-0.3))
    _, feeds_mm, forces_mm, _ = _run(mm, 60)
    _, feeds_fx, forces_fx, _ = _run(fixed, 60)
    np.testing.assert_allclose(feeds_mm, feeds_fx, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(forces_mm, forces_fx, rtol=1e-12, atol=1e-9)


def test_scheme1_initial_beta_must_be_a_candidate() -> None:
    with pytest.raises(ParameterError, match='initial_beta'):
        MultiModelScheme1.from_parameters(MODEL, {'betas': [0.5, -0.5], 'initial_beta': 0.0})
    with pytest.raises(ParameterError, match='betas'):
        MultiModelScheme1.from_parameters(MODEL, {'betas': [0.0, 1.5]})
    with pytest.raises(ParameterError, match='forgetting'):
        MultiModelScheme1.from_parameters(MODEL, {'forgetting': 1.5})
    with pytest.raises(ParameterError, match='weight_jump'):
        MultiModelScheme1.from_parameters(MODEL, {'weight_jump': -0.1})


def test_scheme2_moves_by_delta_or_halves_it() -> None:
    ctrl = MultiModelScheme2.from_parameters(MODEL, {'stop_after': 0}, LO, HI)
    betas, _, _, cands = _run(ctrl, 80)
    delta = 0.2
    for k in range(1, len(betas)):
        if k % 2 == 0:  # a decision every τ_R = 2 samples
            prev, now = betas[k - 1], betas[k]
            if now == prev:
                delta /= 2.0  # kept: Δβ ← Δβ/m
            else:
                assert abs(abs(now - prev) - delta) < 1e-12  # moved by ±Δβ, Δβ kept
        else:
            assert betas[k] == betas[k - 1]
        b = betas[k]
        expected = sorted({max(-1.0, b - delta), b, min(1.0, b + delta)})
        assert sorted(cands[k]) == pytest.approx(expected, abs=1e-12)
    assert ctrl.delta_beta == pytest.approx(delta)
    assert np.all(np.abs(betas) <= 1.0)


def test_scheme2_freezes_after_stop_after() -> None:
    ctrl = MultiModelScheme2.from_parameters(MODEL, {'stop_after': 10}, LO, HI)
    betas, _, _, _ = _run(ctrl, 40)
    assert np.all(betas[10:] == betas[10])


@pytest.mark.parametrize('cls', [MultiModelScheme1, MultiModelScheme2])
def test_schemes_are_causal(cls) -> None:
    rng = np.random.default_rng(3)
    n, k0 = 24, 11
    r1 = rng.uniform(900, 1400, n)
    y1 = rng.uniform(500, 1800, n)
    r2, y2 = r1.copy(), y1.copy()
    r2[k0 + 1 :] *= 1.3
    y2[k0 + 1 :] *= 0.6
    outs = []
    for r, y in ((r1, y1), (r2, y2)):
        c = cls.from_parameters(MODEL, {}, LO, HI)
        outs.append(np.array([c.update(rk, yk) for rk, yk in zip(r, y, strict=True)]))
    np.testing.assert_array_equal(outs[0][: k0 + 1], outs[1][: k0 + 1])
    assert np.any(outs[0][k0 + 1 :] != outs[1][k0 + 1 :])


def test_sampled_index_cannot_rank_perfect_models() -> None:
    """Eq. (13) read at the sampling instants: every design tracks its own discrete model,
    so the tracking term is rounding noise for every candidate (our reason for the
    continuous reading)."""
    model = ForceProcessModel(ForceProcessParams(depth_profile=[0.0, 2.0]))
    only_tracking = {'weight_jump': 0.0, 'weight_tracking': 1.0, 'stop_after': 0}
    sampled = MultiModelScheme1.from_parameters(
        model, {**only_tracking, 'index_signal': 'sampled'}, LO, HI
    )
    cont = MultiModelScheme1.from_parameters(
        model, {**only_tracking, 'residence_samples': 1000}, LO, HI
    )
    _run(sampled, 12, model)
    _run(cont, 12, model)
    assert max(sampled.indices()) < 1e-12
    j = np.array(cont.indices())
    assert j.max() > 1.0  # the inter-sample error differs between holds
    assert np.argmin(j) == PAPER_BETAS.index(0.0)  # at the start, the ZOH's is the smallest


def test_non_finite_input_is_refused() -> None:
    ctrl = MultiModelScheme2.from_parameters(MODEL, {}, LO, HI)
    with pytest.raises(ValueError, match='non-finite'):
        ctrl.update(1200.0, math.nan)
