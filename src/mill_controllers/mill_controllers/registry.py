"""Name → controller class, as selected by the node's 'controller' parameter (ROS-free)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from mill_common.registry import Registry

from mill_controllers.adaptive_pi import AdaptivePi, MachinePi
from mill_controllers.base import AxisController
from mill_controllers.cascade_pi import CascadePi
from mill_controllers.excitation import ExcitationController
from mill_controllers.gpi_controller import GpiController
from mill_controllers.pd_law import AdrcController, PdController
from mill_controllers.sliding_gpi import SlidingGpiController

CONTROLLERS: Registry[AxisController] = Registry(
    'controller',
    {
        'adrc': AdrcController,  # Beltrán 2013 eq. (9) with the observer's xi_hat
        'pd': PdController,  # the same law, xi_hat = 0
        'gpi': GpiController,  # Chávez-Conde eq. (9)-(12)
        'sliding_gpi': SlidingGpiController,  # Chávez-Conde eq. (13)-(17)
        'cascade_pi': CascadePi,  # Maharof 2018 §4.1, output in V
        'adaptive_pi': AdaptivePi,  # Hatwesh 2013 self-tuning PI, output in V
        'machine_pi': MachinePi,  # Hatwesh 2013 fixed machine PI, output in V
        'excitation': ExcitationController,  # soft PD hold + binary torque, to identify
    },
)


def controller_class(name: str) -> type[AxisController]:
    """The registered class; ParameterError('controller', …) for an unknown name."""
    return CONTROLLERS.get(name)


def make_controller(
    name: str, input_gain: float, sample_period: float, values: Mapping[str, Any]
) -> AxisController:
    """Build controller `name` from its parameters (names without the prefix)."""
    return CONTROLLERS.get(name).from_parameters(input_gain, sample_period, values)
