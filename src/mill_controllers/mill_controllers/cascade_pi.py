"""Cascade P position / PI velocity controller of Maharof 2018 §4.1 (ROS-free).

Law at sample k (position in mm and velocity in mm/s inside; the suite's m, m/s at the
interface), fig. 3-4, 6, 8:

    v* = k_v (x_ref − y) [+ ẋ_ref if velocity_feedforward],
    e_v = v* − v̂,
    u = k_p e_v + k_i Σ e_v T − d̂   [V], clipped to ±voltage_limit.

Units: k_v [1/s], k_p [V·s/mm], k_i [V/mm] (the paper prints "Vs²/mm"; k_i multiplies
∫e_v dt [mm], so V/mm is the consistent unit). v̂ is est.velocity (the observer's velocity
estimate, m/s). d̂ is est.disturbance, which must be an input-equivalent voltage with
y = G·(u + d) (Imbdo, Dfo, ImbdoDfo): it is subtracted inside the velocity loop, i.e. from
the voltage. compensate = false gives the paper's plain cascade P/PI (configuration (i)).

The paper's fig. 3 has no velocity feed-forward: the Table 1 errors of the plain loop
(MTE 0.148 mm on a 10 mm, 0.5 Hz sine) equal the lag error ẋ_ref/k_v = 31.4/225 = 0.140 mm,
so it defaults to off.

Integrator: backward Euler with anti-windup by conditional integration (the integral is
not advanced while the output is saturated in the direction the error would push it).
input_gain (the suite's torque-model b) is not used: the output is a voltage.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from mill_common.declared import ParamSet, param
from mill_common.parameters import (
    ParameterError,
    boolean,
    non_negative,
    positive,
    positive_or_inf,
)
from mill_common.signals import ControlInputs

from mill_controllers.base import AxisController

MM_PER_M = 1000.0

# ±10 V: the usual analogue velocity/torque command range of servo amplifiers (and of the
# dSPACE DS1104 DAC the paper uses).
DEFAULT_VOLTAGE_LIMIT = 10.0


@dataclass(frozen=True)
class CascadePiGains(ParamSet):
    """The cascade's gains (§4.1), the voltage saturation and the two switches."""

    PREFIX: ClassVar[str] = 'cascade_pi'
    k_v: float = param(225.0, 'position-loop proportional gain k_v, §4.1', positive, unit='1/s')
    k_p: float = param(
        0.00661, 'velocity-loop proportional gain k_p, §4.1', positive, unit='V·s/mm'
    )
    k_i: float = param(
        0.12075,
        'velocity-loop integral gain k_i, §4.1 (printed V·s²/mm)',
        non_negative,
        unit='V/mm',
    )
    voltage_limit: float = param(
        DEFAULT_VOLTAGE_LIMIT,
        'command saturation ±limit [V]; .inf disables it (the paper has none)',
        positive_or_inf,
    )
    compensate: bool = param(
        True,
        'subtract the observer disturbance estimate (volts) in the velocity loop',
        boolean,
    )
    velocity_feedforward: bool = param(
        False,
        'add the reference velocity to the position-loop output (not in the paper)',
        boolean,
    )


class CascadePi(AxisController):
    """Maharof 2018 cascade P/PI with input-voltage disturbance compensation."""

    PARAMS: ClassVar[type[CascadePiGains]] = CascadePiGains
    OUTPUT_UNIT: ClassVar[str] = 'V'  # amplifier input voltage (Maharof eq. (1))
    DISTURBANCE_UNIT: ClassVar[str | None] = 'V'  # d̂, an input-equivalent voltage

    def __init__(
        self,
        input_gain: float,
        sample_period: float,
        params: CascadePiGains = CascadePiGains(),
    ) -> None:
        del input_gain  # voltage output; the loop gains carry the plant's units
        reason = positive(sample_period)
        if reason:
            raise ParameterError('sample_period', sample_period, reason)
        self._T = float(sample_period)
        self._kv, self._kp, self._ki = params.k_v, params.k_p, params.k_i
        self._limit = params.voltage_limit
        self._compensate = params.compensate
        self._feedforward = params.velocity_feedforward
        self._integral = 0.0  # Σ e_v T [mm]

    def compute(self, inputs: ControlInputs) -> float:
        """Voltage [V] from y [m], ref [m, m/s], est.velocity [m/s], est.disturbance [V]."""
        t, y, ref, est = inputs.t, inputs.position, inputs.reference, inputs.estimate
        d_hat = est.disturbance if self._compensate else 0.0
        read = (t, y, ref.position, ref.velocity, est.velocity, d_hat)
        if not all(math.isfinite(x) for x in read):
            raise ValueError(
                f'CascadePi: non-finite input (t={t!r}, y={y!r}, ref={ref!r}, '
                f'velocity estimate={est.velocity!r}, disturbance estimate={d_hat!r})'
            )
        # Maharof 2018 §4.1 fig. 3: v* = k_v (x_ref − x)   [mm/s]
        v_ref = self._kv * (ref.position - y) * MM_PER_M
        if self._feedforward:
            v_ref += ref.velocity * MM_PER_M
        e_v = v_ref - est.velocity * MM_PER_M
        integral = self._integral + e_v * self._T
        # Maharof 2018 §4.1, fig. 4: u = k_p e_v + k_i ∫e_v dt − d̂   [V]
        u = self._kp * e_v + self._ki * integral - d_hat
        if u > self._limit or u < -self._limit:
            u_sat = min(self._limit, max(-self._limit, u))
            # Conditional integration: keep the integral only if it pulls out of saturation.
            if e_v * (u - u_sat) <= 0.0:
                self._integral = integral
            return u_sat
        self._integral = integral
        return u

    def reset(self) -> None:
        self._integral = 0.0

    @property
    def integral(self) -> float:
        """Σ e_v T [mm]."""
        return self._integral

    @property
    def voltage_limit(self) -> float:
        return self._limit
