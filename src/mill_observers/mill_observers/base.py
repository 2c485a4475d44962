"""Interface of a per-axis observer (ROS-free).

Each sample k the node calls, in this order:

1. ``est = observer.correct(y)``  -- measurement update with the position measured at k;
   returns the estimate at k (current-estimator form), so the controller can use it in the
   same sample. The first call initialises the state from y (position = y, the rest 0).
2. ``observer.predict(u)``  -- time update with the command u [N·m] held over the next
   sample period (zero-order hold).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar, Protocol, runtime_checkable

from mill_common.parameters import ParamSpec
from mill_common.signals import Estimate


@runtime_checkable
class Observer(Protocol):
    """One axis: position measurement in, position/velocity/disturbance estimate out."""

    def correct(self, y: float) -> Estimate:
        """Measurement update with the position y [m] measured at this sample."""
        ...

    def predict(self, u: float) -> None:
        """Time update with the command u [N·m] held constant over the next period."""
        ...


class ObserverClass(Protocol):
    """What a registry entry offers: its parameter namespace, specs and a factory."""

    PREFIX: ClassVar[str]
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]]

    @classmethod
    def from_parameters(
        cls, input_gain: float, sample_period: float, values: Mapping[str, Any]
    ) -> Observer: ...
