"""Name → observer class, as selected by the node's 'observer' parameter (ROS-free)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from mill_common.registry import Registry

from mill_observers.base import Observer
from mill_observers.dfo import Dfo
from mill_observers.eso import ExtendedStateObserver
from mill_observers.gpi import GpiObserver
from mill_observers.imbdo import Imbdo
from mill_observers.imbdo_dfo import ImbdoDfo
from mill_observers.rls_observer import RlsObserver

OBSERVERS: Registry[Observer] = Registry(
    'observer',
    {
        'gpi': GpiObserver,  # Beltrán 2013 eq. (13)-(18)
        'eso': ExtendedStateObserver,  # one bandwidth (Gao 2003), the tuning rule's
        'imbdo': Imbdo,  # Maharof 2018, inverse model + Q filter, estimate in V
        'dfo': Dfo,  # Maharof 2018 eq. (10)-(11), estimate in V
        'imbdo_dfo': ImbdoDfo,  # both, as in the paper
        'rls': RlsObserver,  # Hatwesh 2013 eq. (10)-(13), FOPDT estimates on observer_state
    },
)


def observer_class(name: str) -> type[Observer]:
    """The registered class; ParameterError('observer', …) for an unknown name."""
    return OBSERVERS.get(name)


def make_observer(
    name: str, input_gain: float, sample_period: float, values: Mapping[str, Any]
) -> Observer:
    """Build observer `name` from its parameters (names without the prefix)."""
    return OBSERVERS.get(name).from_parameters(input_gain, sample_period, values)
