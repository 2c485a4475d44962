"""Table 1 values and parameter validation of the rigid axis (Beltrán 2013 eq. (2), (5))."""

from __future__ import annotations

import math

import pytest
from mill_models.axis_data import BELTRAN_TABLE1, RigidAxisParams, nominal_input_gain

A = 0.003175 / (2.0 * math.pi)  # lead [m/rad], computed by hand from p


@pytest.mark.parametrize(
    ('axis', 'mass', 'inertia_kg_mm2'),
    [('x', 17.551, 19.623), ('y', 23.896, 11.872), ('z', 22.505, 16.249)],
)
def test_table1_derived_values(axis: str, mass: float, inertia_kg_mm2: float) -> None:
    params = BELTRAN_TABLE1[axis]
    m_e = mass + inertia_kg_mm2 * 1e-6 / A**2
    assert params.lead == pytest.approx(A, rel=1e-15)
    assert params.effective_mass == pytest.approx(m_e, rel=1e-14)
    assert params.effective_damping == 5.0  # c_b + c_t, both 2.5 N s/m (translational reading)
    assert params.input_gain == pytest.approx(1.0 / (A * m_e), rel=1e-14)
    assert nominal_input_gain(axis) == params.input_gain
    assert params.coulomb_friction == 0.3


def test_table1_magnitudes_catch_unit_mistakes() -> None:
    # J in kg·mm² converted to kg·m²: the screw adds tens of kg, not 1e6 kg or 1e-5 kg.
    assert BELTRAN_TABLE1['x'].effective_mass == pytest.approx(94.3999, abs=1e-3)
    assert BELTRAN_TABLE1['y'].effective_mass == pytest.approx(70.3899, abs=1e-3)
    assert BELTRAN_TABLE1['z'].effective_mass == pytest.approx(86.1404, abs=1e-3)
    assert BELTRAN_TABLE1['x'].input_gain == pytest.approx(20.9635, abs=1e-3)
    # Slow plant pole c_e/m_e (the literal c_t/a^2 reading would put it near -1e5 1/s).
    for params in BELTRAN_TABLE1.values():
        assert 0.05 < params.effective_damping / params.effective_mass < 0.08


def _good(**changes: float) -> dict[str, float]:
    values = dict(
        mass=1.0,
        screw_inertia=1e-5,
        pitch=0.005,
        cart_damping=1.0,
        screw_damping=1.0,
        coulomb_friction=0.1,
    )
    values.update(changes)
    return values


@pytest.mark.parametrize(
    ('field', 'value'),
    [
        ('mass', 0.0),
        ('mass', -1.0),
        ('screw_inertia', 0.0),
        ('pitch', -0.001),
        ('cart_damping', -0.1),
        ('screw_damping', -0.1),
        ('coulomb_friction', -0.1),
        ('mass', math.nan),
        ('pitch', math.inf),
        ('coulomb_friction', math.nan),
    ],
)
def test_invalid_parameters_are_refused_by_name(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=field):
        RigidAxisParams(**_good(**{field: value}))


def test_zero_damping_and_friction_are_allowed() -> None:
    params = RigidAxisParams(**_good(cart_damping=0.0, screw_damping=0.0, coulomb_friction=0.0))
    assert params.effective_damping == 0.0


def test_unknown_axis_is_refused() -> None:
    with pytest.raises(ValueError, match='w'):
        nominal_input_gain('w')
