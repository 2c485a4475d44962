"""The controller node's parameters and how they build the core (ROS-free)."""

from __future__ import annotations

from typing import Any

import pytest
from mill_common.parameters import ParameterError
from mill_controllers.adaptive_pi import AdaptivePi, AdaptivePiParams
from mill_controllers.config import (
    ControllerNodeParams,
    build_controller,
    parameter_specs,
    rebuilds_law,
    unseen_input,
)
from mill_controllers.pd_law import AdrcController
from mill_models.loop_tuning import loop_tuning


def _values(**changes: Any) -> dict[str, Any]:
    values = {name: spec.default for name, spec in parameter_specs()}
    values.update(changes)
    return values


def test_the_node_parameters_are_declared_once_each() -> None:
    names = [name for name, _ in parameter_specs()]
    assert len(names) == len(set(names))
    own = [name for name, _ in ControllerNodeParams.named_specs()]
    assert own == [
        'excursion',
        'max_hold',
        'hold_deviation',
        'stall_report',
        'controller',
        'blend_time',
        'observer_node',
        'trajectory_node',
        'following_error_limit',
        'gap_trip',
        'min_following_error',
        'max_velocity',
    ]
    assert all(name in names for name in own)


def test_a_zero_bandwidth_takes_the_tuning_rule() -> None:
    values = _values(**{'controller': 'adrc', 'pd.omega_c': 0.0, 'design_period': 0.0})
    ctrl = build_controller(values)
    assert isinstance(ctrl, AdrcController)
    rule = loop_tuning(values['sample_period'], values['command_delay'])
    assert ctrl.alpha0 == pytest.approx(rule.omega_c**2)


def test_a_given_bandwidth_is_kept() -> None:
    ctrl = build_controller(_values(**{'controller': 'adrc', 'pd.omega_c': 20.0}))
    assert isinstance(ctrl, AdrcController)
    assert ctrl.alpha0 == pytest.approx(400.0)


def test_only_fields_declared_with_the_rule_are_tuned() -> None:
    # excitation.omega_c is declared positive, without the rule: 0 is refused, not tuned
    with pytest.raises(ParameterError, match=r'excitation\.omega_c'):
        build_controller(_values(**{'controller': 'excitation', 'excitation.omega_c': 0.0}))


def test_a_change_of_limit_blend_or_input_watch_keeps_the_law_any_other_replaces_it() -> None:
    old = _values()
    assert not rebuilds_law(_values(**{'following_error_limit': 2e-3, 'blend_time': 0.2}), old)
    assert not rebuilds_law(_values(**{'input_warn_time': 5.0, 'input_timeout': 50.0}), old)
    assert rebuilds_law(_values(controller='gpi'), old)
    assert rebuilds_law(_values(**{'pd.omega_c': 20.0}), old)  # a gain: a new law
    assert not rebuilds_law(old, old)


def test_a_law_reading_the_observers_model_waits_for_a_sample_of_it() -> None:
    outside = AdaptivePi(0.0, 1e-3, AdaptivePiParams(model_source='observer'))
    own = AdaptivePi(0.0, 1e-3, AdaptivePiParams())
    assert unseen_input(outside, {'position', 'estimate'}) == 'model'
    assert unseen_input(outside, {'position', 'estimate', 'model'}) is None
    assert unseen_input(own, set()) is None  # the base inputs are never asked for here
