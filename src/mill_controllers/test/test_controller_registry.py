"""Controller registry: names, factory, refusals naming the parameter."""

from __future__ import annotations

import pytest
from mill_common.parameters import ParameterError
from mill_controllers.adaptive_pi import AdaptivePi, MachinePi
from mill_controllers.cascade_pi import CascadePi
from mill_controllers.excitation import ExcitationController
from mill_controllers.gpi_controller import GpiController
from mill_controllers.pd_law import AdrcController, PdController
from mill_controllers.registry import CONTROLLERS, controller_class, make_controller
from mill_controllers.sliding_gpi import SlidingGpiController

B = 20.96


def test_registered_names() -> None:
    assert {
        'adrc': AdrcController,
        'pd': PdController,
        'gpi': GpiController,
        'sliding_gpi': SlidingGpiController,
        'cascade_pi': CascadePi,
        'adaptive_pi': AdaptivePi,
        'machine_pi': MachinePi,
        'excitation': ExcitationController,
    } == dict(CONTROLLERS.items())
    assert controller_class('pd') is PdController


def test_factory_builds_with_values() -> None:
    ctrl = make_controller('adrc', B, 1e-3, {'omega_c': 15.0})
    assert isinstance(ctrl, AdrcController)
    assert ctrl.alpha0 == pytest.approx(225.0)
    assert isinstance(make_controller('pd', B, 1e-3, {}), PdController)


@pytest.mark.parametrize('name', ['PD', 'lqr', '', 'sliding', None])
def test_unknown_controller(name: object) -> None:
    with pytest.raises(ParameterError) as info:
        make_controller(name, B, 1e-3, {})  # type: ignore[arg-type]
    assert info.value.name == 'controller'
    assert 'must be one of: adrc, pd' in str(info.value)


@pytest.mark.parametrize(('name', 'param'), [('adrc', 'omega_c'), ('pd', 'zeta_c')])
def test_bad_value_names_prefixed_parameter(name: str, param: str) -> None:
    with pytest.raises(ParameterError) as info:
        make_controller(name, B, 1e-3, {param: -1.0})
    assert info.value.name == f'pd.{param}'
