"""A carriage whose velocity crosses zero inside a substep: 'stop' dwells, 'through' goes on."""

from __future__ import annotations

import dataclasses

import pytest
from mill_plant.axis_plant import AxisPlant
from mill_plant.cutting import NoCutting
from mill_plant.models.rigid import RigidAxisModel

DT = 1e-3
V0 = 0.01  # [m/s], x moving +
TORQUE = -0.5  # [N m], far above breakaway the other way


def _undamped() -> list[RigidAxisModel]:
    """Rigid axes without viscous damping: the velocity is piecewise linear in time."""
    models = [RigidAxisModel.from_parameters(i, {}) for i in range(3)]
    for m in models:
        m.params = dataclasses.replace(m.params, cart_damping=0.0, screw_damping=0.0)
        m._update()
    return models


def _one_step(reversal: str) -> tuple[AxisPlant, RigidAxisModel]:
    models = _undamped()
    plant = AxisPlant(models, NoCutting(), substeps=1, reversal=reversal)
    plant._state[0][1] = V0  # no public state setter
    plant.step((TORQUE, 0.0, 0.0), DT)
    return plant, models[0]


def test_through_reverses_at_once_and_is_exact() -> None:
    plant, model = _one_step('through')
    p = model.params
    mu = model.coulomb_friction
    # m_e v' = τ/a − μ sign(v): decelerate to 0 at t_c, then accelerate the other way.
    slow = (TORQUE / p.lead - mu) / p.effective_mass
    back = (TORQUE / p.lead + mu) / p.effective_mass
    t_c = -V0 / slow
    assert 0.0 < t_c < DT  # the crossing is inside the step
    v = back * (DT - t_c)
    x = V0 * t_c / 2.0 + 0.5 * back * (DT - t_c) ** 2
    assert plant.velocity[0] == pytest.approx(v, rel=1e-12)
    assert plant.position[0] == pytest.approx(x, rel=1e-12)


def test_stop_dwells_at_rest_for_the_rest_of_the_substep() -> None:
    plant, _ = _one_step('stop')
    assert plant.velocity[0] == 0.0
    assert plant.position[0] > 0.0


def test_an_unknown_reversal_is_refused() -> None:
    with pytest.raises(ValueError, match='reversal must be one of stop, through'):
        AxisPlant(_undamped(), NoCutting(), reversal='bounce')
