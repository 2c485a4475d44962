"""Interface of a per-axis controller (ROS-free)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar, Protocol, runtime_checkable

from mill_common.parameters import ParamSpec
from mill_common.signals import AxisReference, Estimate


@runtime_checkable
class AxisController(Protocol):
    """One axis: measured position, reference and observer estimate in, torque out."""

    def compute(self, t: float, y: float, ref: AxisReference, est: Estimate) -> float:
        """Torque command [N·m] at time t [s] from the measured position y [m]."""
        ...


class ControllerClass(Protocol):
    """What a registry entry offers: its parameter namespace, specs and a factory."""

    PREFIX: ClassVar[str]
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]]

    @classmethod
    def from_parameters(
        cls, input_gain: float, sample_period: float, values: Mapping[str, Any]
    ) -> AxisController: ...
