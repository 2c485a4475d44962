"""The observer contract: declarations every observer has, with their defaults."""

from __future__ import annotations

import pytest
from mill_observers.base import Observer
from mill_observers.registry import OBSERVERS, make_observer

B = 20.96
VOLTAGE_ESTIMATES = {'imbdo', 'dfo', 'imbdo_dfo'}  # Maharof: input-equivalent voltage


@pytest.mark.parametrize('name', OBSERVERS.names())
def test_every_observer_declares_the_contract(name: str) -> None:
    cls = OBSERVERS.get(name)
    assert issubclass(cls, Observer)
    assert ('V' if name in VOLTAGE_ESTIMATES else 'm/s²') == cls.DISTURBANCE_UNIT
    assert (name == 'rls') == cls.PROVIDES_MODEL
    obs = make_observer(name, B, 1e-3, {})
    est = obs.correct(0.01)
    assert est.position == 0.01
    model = obs.model_estimate()
    assert (model is not None) == cls.PROVIDES_MODEL
    assert bool(obs.status()) == cls.PROVIDES_MODEL  # only rls has a state to publish
