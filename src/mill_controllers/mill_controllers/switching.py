"""Bumpless run-time replacement of a control law (ROS-free).

When the node's `controller` parameter (or a gain) changes while a job runs, the new law
starts from the current measurement, reference and estimate at the next sample k_s. At that
sample both laws are evaluated on the same inputs and the output is the OLD law's value:

    u(k_s) = u_old(k_s),  δ = u_old(k_s) − u_new(k_s),
    u(k)   = u_new(k) + δ·r^(k − k_s),  r = e^{−T/blend_time}  for k > k_s,

so the command changes at the switch exactly as much as the old law would have changed it
in that sample, and the difference between the laws fades with the time constant
`blend_time` instead of appearing as a step (classic bumpless transfer by a decaying
offset; it works for any pair of laws, with or without integrators).

Laws whose outputs are in different units (torque N·m against amplifier voltage V) cannot
replace each other on a running plant: `check_replacement` names the reason.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mill_common.signals import ControlInputs

from mill_controllers.base import AxisController
from mill_controllers.registry import CONTROLLERS


def check_replacement(old: type[AxisController], new: type[AxisController]) -> str | None:
    """None if `new` may replace `old` on a running plant, else the reason it may not."""
    if old.OUTPUT_UNIT != new.OUTPUT_UNIT:
        return (
            f'{law_name(new)} commands {new.OUTPUT_UNIT} but the running {law_name(old)} '
            f'commands {old.OUTPUT_UNIT}: the plant input cannot change unit mid-job'
        )
    return None


def law_name(cls: type[AxisController]) -> str:
    """The `controller` value that selects a law: its PREFIX is only its parameters'
    namespace, which laws share (adrc runs on the pd.* gains)."""
    return CONTROLLERS.name_of(cls) or cls.__name__


@dataclass(frozen=True)
class SwitchRecord:
    """What happened at a switch: time [s], the old and new laws' outputs there."""

    time: float
    old_output: float
    new_output: float

    @property
    def offset(self) -> float:
        return self.old_output - self.new_output


class BumplessSwitch:
    """The active control law, replaceable between samples without a bump."""

    def __init__(self, law: AxisController, sample_period: float, blend_time: float) -> None:
        if not (math.isfinite(sample_period) and sample_period > 0.0):
            raise ValueError(f'sample_period must be > 0, got {sample_period!r}')
        self._law = law
        self._old: AxisController | None = None
        self._offset = 0.0
        self.set_blend_time(sample_period, blend_time)
        self.last_switch: SwitchRecord | None = None

    @property
    def law(self) -> AxisController:
        return self._law

    def set_blend_time(self, sample_period: float, blend_time: float) -> None:
        if not blend_time >= 0.0:
            raise ValueError(f'blend_time must be >= 0, got {blend_time!r}')
        self._decay = math.exp(-sample_period / blend_time) if blend_time > 0.0 else 0.0

    def replace(self, law: AxisController) -> None:
        """Use `law` from the next sample on; that sample still outputs the old law's value."""
        if self._old is None:
            self._old = self._law  # two changes before one sample: the first old law stays
        self._law = law

    def compute(self, inputs: ControlInputs) -> float:
        u_new = self._law.compute(inputs)
        if self._old is not None:
            u_old = self._old.compute(inputs)
            self._old = None
            self._offset = u_old - u_new
            self.last_switch = SwitchRecord(inputs.t, u_old, u_new)
            return u_old
        if self._offset != 0.0:
            self._offset *= self._decay
            if abs(self._offset) < 1e-300:
                self._offset = 0.0
        return u_new + self._offset
