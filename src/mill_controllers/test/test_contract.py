"""The controller contract: declarations every law has, and the inputs the node joins."""

from __future__ import annotations

from dataclasses import fields

import pytest
from mill_common.signals import JOINED_INPUTS, AxisReference, ControlInputs, Estimate
from mill_controllers.adaptive_pi import AdaptivePi, AdaptivePiParams
from mill_controllers.base import BASE_INPUTS, AxisController
from mill_controllers.controller_inputs import INPUTS
from mill_controllers.registry import CONTROLLERS, make_controller
from mill_controllers.switching import check_replacement

B = 20.96
VOLTAGE_LAWS = {'cascade_pi', 'adaptive_pi', 'machine_pi'}  # Maharof and Hatwesh: V out


@pytest.mark.parametrize('name', CONTROLLERS.names())
def test_every_law_declares_the_contract(name: str) -> None:
    cls = CONTROLLERS.get(name)
    assert issubclass(cls, AxisController)
    assert ('V' if name in VOLTAGE_LAWS else 'N·m') == cls.OUTPUT_UNIT
    law = make_controller(name, B, 1e-3, {})
    assert law.required_inputs() == BASE_INPUTS  # defaults: no model needed
    ref = AxisReference(0.001, 0.01, 0.0)
    u = law.compute(ControlInputs(0.0, 0.0, ref, Estimate(0.0, 0.0, 0.0)))
    assert u != 0.0  # 1 mm and 10 mm/s behind: a command
    law.reset()
    assert law.compute(ControlInputs(0.0, 0.0, ref, Estimate(0.0, 0.0, 0.0))) == u


def test_status_is_empty_unless_the_law_has_estimates() -> None:
    assert make_controller('adrc', B, 1e-3, {}).status() == {}
    assert 'k_p' in make_controller('adaptive_pi', B, 1e-3, {}).status()


def test_a_law_designing_with_the_observers_model_requires_it() -> None:
    law = AdaptivePi(0.0, 1e-3, AdaptivePiParams(model_source='observer'))
    assert law.needs_model
    assert law.required_inputs() == (*BASE_INPUTS, 'model')


def test_the_node_has_a_topic_for_every_joined_input() -> None:
    names = [f.name for f in fields(ControlInputs)]
    assert tuple(n for n in names if n != 't') == JOINED_INPUTS
    assert set(INPUTS) == set(JOINED_INPUTS)
    assert set(BASE_INPUTS) <= set(JOINED_INPUTS)


def test_replacement_only_within_one_output_unit() -> None:
    assert check_replacement(CONTROLLERS.get('adrc'), CONTROLLERS.get('gpi')) is None
    assert check_replacement(CONTROLLERS.get('machine_pi'), CONTROLLERS.get('cascade_pi')) is None
    reason = check_replacement(CONTROLLERS.get('adrc'), CONTROLLERS.get('cascade_pi'))
    assert reason is not None and 'cascade_pi commands V' in reason
