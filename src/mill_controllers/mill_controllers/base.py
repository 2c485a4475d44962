"""The contract of a per-axis controller (ROS-free).

Every control law subclasses AxisController. What the node and the offline simulator may
rely on is declared here, with defaults a law overrides only where it differs:

- PREFIX, PARAMETERS: the parameter namespace and the parameters (mill_common.parameters);
- OUTPUT_UNIT: the unit of the command, the plant's input: motor torque 'N·m' or
  amplifier voltage 'V';
- needs_model / required_inputs(): which fields of ControlInputs the law reads beyond
  the measured position, the reference and the observer's estimate (the node waits for
  exactly these by stamp);
- status(): internal estimates worth publishing each sample (none by default);
- reset(): forget the past (nothing to forget by default).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import Any, ClassVar, TypeVar

from mill_common.declared import Configured, ParamSet
from mill_common.parameters import check_gain_and_period
from mill_common.signals import ControlInputs

__all__ = ['AxisController', 'check_gain_and_period']

C = TypeVar('C', bound='AxisController')

# The inputs every law gets (fields of ControlInputs joined by stamp).
BASE_INPUTS: tuple[str, ...] = ('position', 'estimate', 'reference')


def saturate(value: float, limit: float) -> float:
    """`value` clipped to ±limit; NaN stays NaN (min/max would turn it into a limit): a law
    whose gains or states are not finite gives no command, and the loop asks for the brake
    (mill_controllers.control_loop) instead of sending a full-scale one."""
    return value if math.isnan(value) else min(limit, max(-limit, value))


class AxisController(Configured, ABC):
    """One axis: measured position, reference and observer estimate in, command out.

    A law is built as `Law(input_gain, sample_period, params)`, params its PARAMS set.
    """

    OUTPUT_UNIT: ClassVar[str] = 'N·m'  # motor torque; 'V' for an amplifier voltage
    # The unit the law reads the observer's disturbance estimate in (the observer's
    # DISTURBANCE_UNIT must match: mill_bringup.job_config); None: it does not read it.
    DISTURBANCE_UNIT: ClassVar[str | None] = None

    @classmethod
    def from_parameters(
        cls: type[C], input_gain: float, sample_period: float, values: Mapping[str, Any]
    ) -> C:
        """Build from values named without the prefix (missing names take defaults).

        input_gain: b of the nominal model x'' = b u + ξ [m/s² per N·m]; sample_period T
        [s]. Raises ParameterError naming a bad parameter.
        """
        return cls.from_params(input_gain, sample_period, cls.PARAMS.from_values(values))

    @classmethod
    def from_params(cls: type[C], input_gain: float, sample_period: float, params: ParamSet) -> C:
        """Build from a set of the law's PARAMS (e.g. one the tuning rule has filled in)."""
        return cls(input_gain, sample_period, params)  # type: ignore[call-arg]

    @abstractmethod
    def compute(self, inputs: ControlInputs) -> float:
        """The command in OUTPUT_UNIT for the sample at inputs.t [s].

        Raises ValueError if an input the law reads is not finite or missing.
        """

    @property
    def needs_model(self) -> bool:
        """True if compute() reads inputs.model, the observer's identified plant model."""
        return False

    def required_inputs(self) -> tuple[str, ...]:
        """The ControlInputs fields compute() needs each sample (the node joins them)."""
        return (*BASE_INPUTS, 'model') if self.needs_model else BASE_INPUTS

    def status(self) -> dict[str, float]:
        """Internal quantities of the last sample, name → value (published if any)."""
        return {}

    def reset(self) -> None:
        """Start afresh, as just built (a law without memory has nothing to do)."""
