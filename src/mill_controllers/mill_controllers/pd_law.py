"""PD tracking law with disturbance compensation of Beltrán 2013 eq. (9)-(12) (ROS-free).

Two variants share the law and the parameter namespace 'pd':

- AdrcController subtracts the observer's disturbance estimate ξ̂ (the paper's figs. 8-10);
- PdController sets ξ̂ ≡ 0 (the paper's uncompensated figs. 5-7) but still uses the
  observer's velocity estimate, as the paper does.

Non-finite inputs raise ValueError (the node catches and logs it) instead of returning a
NaN or a clipped-garbage torque that would look like a valid command.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from mill_common.declared import ParamSet, param
from mill_common.parameters import ParameterError, non_negative, positive, positive_or_inf
from mill_common.signals import ControlInputs

from mill_controllers.base import AxisController, check_gain_and_period, saturate

# 5 N·m: about the peak torque of the ~0.75 kW AC servo that drives a small mill's ball
# screw. The paper's cut needs well under 1 N·m with the realistic cutting-energy reading,
# so the paper's runs never saturate, yet a diverging observer cannot command an absurd
# torque. Set inf to reproduce the paper's unsaturated law exactly.
DEFAULT_TORQUE_LIMIT = 5.0


@dataclass(frozen=True)
class TorqueLimited(ParamSet):
    """The torque saturation of a law that commands a torque (shared by the laws)."""

    torque_limit: float = param(
        DEFAULT_TORQUE_LIMIT,
        'torque command saturation ±limit; .inf disables it (the paper has none)',
        positive_or_inf,
        unit='N·m',
    )


@dataclass(frozen=True)
class PdGains(TorqueLimited):
    """The law's parameters, eq. (12) and the saturation."""

    PREFIX: ClassVar[str] = 'pd'
    omega_c: float = param(
        12.0,
        'natural frequency ω_c of the tracking-error dynamics, eq. (12)',
        non_negative,
        unit='rad/s',
        rule='omega_c',
    )
    zeta_c: float = param(
        0.7071, 'damping ratio ζ_c of the tracking-error dynamics, eq. (12)', positive, unit='-'
    )


class _PdLaw(AxisController):
    """Beltrán 2013 eq. (9) for one axis; subclasses choose whether ξ̂ is compensated."""

    PARAMS: ClassVar[type[PdGains]] = PdGains
    COMPENSATE: ClassVar[bool] = True

    def __init__(
        self, input_gain: float, sample_period: float, params: PdGains = PdGains()
    ) -> None:
        self._b, self._T = check_gain_and_period(input_gain, sample_period)
        if params.omega_c == 0.0:
            raise ParameterError('pd.omega_c', 0.0, 'the tuning rule is resolved by the node')
        self._omega_c = params.omega_c
        self._zeta_c = params.zeta_c
        self._limit = params.torque_limit
        # Beltrán 2013 eq. (11)-(12), misprint fixed: p_d(s) = s² + 2 ζ_c ω_c s + ω_c²
        self._alpha1 = 2.0 * self._zeta_c * self._omega_c
        self._alpha0 = self._omega_c * self._omega_c

    @property
    def alpha0(self) -> float:
        """α0 = ω_c² [1/s²]."""
        return self._alpha0

    @property
    def alpha1(self) -> float:
        """α1 = 2 ζ_c ω_c [1/s]."""
        return self._alpha1

    @property
    def torque_limit(self) -> float:
        return self._limit

    @property
    def input_gain(self) -> float:
        return self._b

    def compute(self, inputs: ControlInputs) -> float:
        """Torque [N·m], clipped to ±torque_limit.

        Uses the measured position y, the reference and est.velocity; est.disturbance
        only when compensating. Raises ValueError if any value it reads is not finite.
        """
        t, y, ref, est = inputs.t, inputs.position, inputs.reference, inputs.estimate
        xi_hat = est.disturbance if self.COMPENSATE else 0.0
        finite = math.isfinite  # each value by name (no generator: 3 calls a sample)
        if not (
            finite(t)
            and finite(y)
            and finite(ref.position)
            and finite(ref.velocity)
            and finite(ref.acceleration)
            and finite(est.velocity)
            and finite(xi_hat)
        ):
            raise ValueError(
                f'{type(self).__name__}: non-finite input (t={t!r}, y={y!r}, ref={ref!r}, '
                f'velocity estimate={est.velocity!r}, disturbance estimate={xi_hat!r})'
            )
        # Beltrán 2013 eq. (9): τ = (1/b)[ẍ* − α1(v̂ − ẋ*) − α0(x − x*) − ξ̂]
        tau = (
            ref.acceleration
            - self._alpha1 * (est.velocity - ref.velocity)
            - self._alpha0 * (y - ref.position)
            - xi_hat
        ) / self._b
        return saturate(tau, self._limit)


class AdrcController(_PdLaw):
    """Eq. (9) with the observer's disturbance estimate compensated (paper figs. 8-10)."""

    COMPENSATE: ClassVar[bool] = True
    DISTURBANCE_UNIT: ClassVar[str | None] = 'm/s²'  # ξ̂ of eq. (9), an acceleration


class PdController(_PdLaw):
    """Eq. (9) with ξ̂ ≡ 0 (paper figs. 5-7); still uses the observer's velocity."""

    COMPENSATE: ClassVar[bool] = False
