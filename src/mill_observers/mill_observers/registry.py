"""Name → observer class, as selected by the node's 'observer' parameter (ROS-free)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from mill_common.parameters import ParameterError

from mill_observers.base import Observer
from mill_observers.dfo import Dfo
from mill_observers.gpi import GpiObserver
from mill_observers.imbdo import Imbdo
from mill_observers.imbdo_dfo import ImbdoDfo
from mill_observers.rls_observer import RlsObserver

OBSERVERS: dict[str, type] = {
    'gpi': GpiObserver,  # Beltrán 2013 eq. (13)-(18)
    'imbdo': Imbdo,  # Maharof 2018, inverse model + Q filter, estimate in V
    'dfo': Dfo,  # Maharof 2018 eq. (10)-(11), estimate in V
    'imbdo_dfo': ImbdoDfo,  # both, as in the paper
    'rls': RlsObserver,  # Hatwesh 2013 eq. (10)-(13), FOPDT estimates on observer_state
}


def observer_class(name: str) -> type:
    """The registered class; ParameterError('observer', …) for an unknown name."""
    try:
        return OBSERVERS[name]
    except (KeyError, TypeError):
        raise ParameterError('observer', name, f'must be one of: {", ".join(OBSERVERS)}') from None


def make_observer(
    name: str, input_gain: float, sample_period: float, values: Mapping[str, Any]
) -> Observer:
    """Build observer `name` from its parameters (names without the prefix)."""
    return observer_class(name).from_parameters(input_gain, sample_period, values)
