"""--tuning rule: what the laws and observers declare decides which are tuned and how."""

from __future__ import annotations

import pytest
from mill_bringup.catalogue import CONTROLLER, OBSERVER
from mill_bringup.cli import rule_laws, rule_observer, set_tuning
from mill_bringup.scenario import ScenarioError

from mill_bringup import scenario


def test_the_rule_tunes_the_laws_and_the_observer_that_declare_it() -> None:
    assert rule_laws() == ('adrc', 'pd')  # pd_law's PdGains: omega_c, rule='omega_c'
    assert rule_observer() == 'eso'  # EsoParams: omega_o, rule='omega_o'


def test_every_axis_runs_the_rule_observer_at_the_rules_bandwidths() -> None:
    scen = scenario.load('slotting')
    set_tuning(scen)
    for node in scen.nodes_of(CONTROLLER):
        params = scen.parameters(node.name)
        assert params['controller'] in rule_laws()
        assert (params['pd.omega_c'], params['design_period']) == (0.0, 0.0)
    assert scen.nodes_of(OBSERVER)
    for node in scen.nodes_of(OBSERVER):
        params = scen.parameters(node.name)
        assert params['observer'] == 'eso'
        assert (params['eso.omega_o'], params['design_period']) == (0.0, 0.0)


def test_a_law_that_declares_no_rule_field_is_refused_naming_those_that_do() -> None:
    scen = scenario.load('slotting')
    scen.add_override('*_controller.controller=gpi')
    with pytest.raises(ScenarioError) as info:
        set_tuning(scen)
    message = str(info.value)
    assert message.startswith('--tuning rule tunes the adrc or pd law with the eso observer; ')
    assert message.endswith('runs gpi')
