"""The observer node's parameters and how they build the core: the tuning rule where a
parameter declares one, the ESO's bandwidth_factor on top."""

from __future__ import annotations

import pytest
from mill_models.loop_tuning import loop_tuning
from mill_observers.config import ObserverNodeParams, build_observer, parameter_specs
from mill_observers.eso import ExtendedStateObserver


def _values(**changes: object) -> dict:
    values = {name: spec.default for name, spec in parameter_specs()}
    values.update(changes)
    return values


def test_the_node_declares_its_own_parameters_once() -> None:
    specs = dict(parameter_specs())
    for spec in ObserverNodeParams.specs():
        assert specs[spec.name] == spec
    assert specs['controller_node'].read_only and not specs['blend_time'].read_only
    assert specs['blend_time'].description.endswith(" to the new one's [s]")
    assert len(specs) == len(parameter_specs())  # each full name once


@pytest.mark.parametrize(('delay', 'factor'), [(0, 1.0), (1, 1.0), (2, 0.5)])
def test_eso_omega_o_0_is_the_rule_for_the_nodes_rate_and_delay(delay: int, factor: float) -> None:
    values = _values(
        observer='eso', sample_period=0.002, command_delay=delay, **{'eso.bandwidth_factor': factor}
    )
    obs = build_observer(values)
    assert isinstance(obs, ExtendedStateObserver)
    assert obs.omega_o == loop_tuning(0.002, delay).omega_o * factor


def test_a_given_bandwidth_is_kept() -> None:
    values = _values(observer='eso', command_delay=1, **{'eso.omega_o': 123.0})
    obs = build_observer(values)
    assert isinstance(obs, ExtendedStateObserver)
    assert obs.omega_o == 123.0
