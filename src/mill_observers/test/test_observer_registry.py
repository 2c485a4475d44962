"""Observer registry: names, factory, refusals naming the parameter."""

from __future__ import annotations

import pytest
from mill_common.parameters import ParameterError
from mill_observers.dfo import Dfo
from mill_observers.eso import ExtendedStateObserver
from mill_observers.gpi import GpiObserver
from mill_observers.imbdo import Imbdo
from mill_observers.imbdo_dfo import ImbdoDfo
from mill_observers.registry import OBSERVERS, make_observer, observer_class
from mill_observers.rls_observer import RlsObserver

B = 20.96


def test_registered_names() -> None:
    want = {
        'gpi': GpiObserver,
        'eso': ExtendedStateObserver,
        'imbdo': Imbdo,
        'dfo': Dfo,
        'imbdo_dfo': ImbdoDfo,
        'rls': RlsObserver,
    }
    assert want == dict(OBSERVERS.items())
    assert observer_class('gpi') is GpiObserver


def test_factory_builds_with_values() -> None:
    obs = make_observer('gpi', B, 1e-3, {'omega_o': 600.0})
    assert isinstance(obs, GpiObserver)
    assert obs.sample_period == 1e-3
    assert obs.input_gain == B


@pytest.mark.parametrize('name', ['GPI', 'kalman', '', 'adrc', None])
def test_unknown_observer(name: object) -> None:
    with pytest.raises(ParameterError) as info:
        make_observer(name, B, 1e-3, {})  # type: ignore[arg-type]
    assert info.value.name == 'observer'
    assert 'must be one of: gpi, eso, imbdo, dfo, imbdo_dfo' in str(info.value)


@pytest.mark.parametrize('param', ['omega_o', 'zeta_o', 'pole_o'])
def test_bad_value_names_prefixed_parameter(param: str) -> None:
    with pytest.raises(ParameterError) as info:
        make_observer('gpi', B, 1e-3, {param: 0.0})
    assert info.value.name == f'gpi.{param}'
