"""The contract of a per-axis observer (ROS-free).

Each sample k the node calls, in this order:

1. ``est = observer.correct(y)``  -- measurement update with the position measured at k;
   returns the estimate at k (current-estimator form), so the controller can use it in the
   same sample. The first call initialises the state from y (position = y, the rest 0).
2. ``observer.predict(u)``  -- time update with the command u held over the next sample
   period (zero-order hold), in the plant's input unit (N·m, or V for a voltage drive).

Every observer subclasses Observer; what the node and the offline simulator may rely on is
declared here, with defaults an observer overrides only where it differs:

- PARAMS: the parameters, one ParamSet (mill_common.declared), from which PREFIX and
  PARAMETERS (the namespace and the specs) are derived;
- DISTURBANCE_UNIT: the unit of Estimate.disturbance, an acceleration 'm/s²' (Beltrán
  2013 eq. (5)) or an input-equivalent voltage 'V';
- PROVIDES_MODEL / model_estimate(): whether it identifies a plant model, and the model
  after the last correct() (published within status(), joined by the controller);
- status(): internal quantities worth publishing each sample (none by default);
- reset(): forget the past (nothing to forget by default);
- preload(u): an observer with the model ẍ = b·u + ξ can start from the disturbance a
  known holding input balances (a vertical axis's weight: hold_torque); others cannot.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import Any, ClassVar, TypeVar

from mill_common.declared import Configured
from mill_common.signals import Estimate, FopdtEstimate

Obs = TypeVar('Obs', bound='Observer')


class Observer(Configured, ABC):
    """One axis: position measurement in, position/velocity/disturbance estimate out.

    An observer is built as `Obs(input_gain, sample_period, params)`, params its PARAMS set.
    """

    DISTURBANCE_UNIT: ClassVar[str] = 'm/s²'  # 'V' for an input-equivalent voltage
    PROVIDES_MODEL: ClassVar[bool] = False  # model_estimate() gives an identified model

    @classmethod
    def from_parameters(
        cls: type[Obs], input_gain: float, sample_period: float, values: Mapping[str, Any]
    ) -> Obs:
        """Build from values named without the prefix (missing names take defaults).

        input_gain: b of the nominal model x'' = b u + ξ [m/s² per N·m] (unused by an
        observer with a model of its own); sample_period T [s]. Raises ParameterError
        naming a bad parameter.
        """
        return cls(input_gain, sample_period, cls.PARAMS.from_values(values))  # type: ignore[call-arg]

    @abstractmethod
    def correct(self, y: float) -> Estimate:
        """Measurement update with the position y [m] measured at this sample."""

    @abstractmethod
    def predict(self, u: float) -> None:
        """Time update with the command u held constant over the next period."""

    def model_estimate(self) -> FopdtEstimate | None:
        """The plant model identified up to the last correct(); None unless PROVIDES_MODEL."""
        return None

    def status(self) -> dict[str, float]:
        """Internal quantities of the last sample, name → value (published if any)."""
        return {}

    def reset(self) -> None:
        """Start afresh, as just built."""

    def preload(self, hold_input: float) -> float | None:
        """After the first correct(): take the disturbance to be the one that `hold_input`
        holds at rest (ξ = −b·u); returns it, None if this observer has no such model."""
        return None
