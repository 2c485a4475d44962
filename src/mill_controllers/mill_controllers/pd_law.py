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
from collections.abc import Mapping
from typing import Any, ClassVar

from mill_common.parameters import (
    ParameterError,
    ParamSpec,
    non_negative,
    positive,
    positive_or_inf,
    validate_all,
)
from mill_common.signals import ControlInputs

from mill_controllers.base import AxisController, saturate

# 5 N·m: about the peak torque of the ~0.75 kW AC servo that drives a small mill's ball
# screw. The paper's cut needs well under 1 N·m with the realistic cutting-energy reading,
# so the paper's runs never saturate, yet a diverging observer cannot command an absurd
# torque. Set inf to reproduce the paper's unsaturated law exactly.
DEFAULT_TORQUE_LIMIT = 5.0


class _PdLaw(AxisController):
    """Beltrán 2013 eq. (9) for one axis; subclasses choose whether ξ̂ is compensated."""

    PREFIX: ClassVar[str] = 'pd'
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec(
            'omega_c',
            12.0,
            'natural frequency ω_c of the tracking-error dynamics, eq. (12) [rad/s]; 0 = the '
            'tuning rule for the sample period and command delay (mill_models.loop_tuning)',
            non_negative,
        ),
        ParamSpec(
            'zeta_c',
            0.7071,
            'damping ratio ζ_c of the tracking-error dynamics, eq. (12) [-]',
            positive,
        ),
        ParamSpec(
            'torque_limit',
            DEFAULT_TORQUE_LIMIT,
            'torque command saturation ±limit [N·m]; .inf disables it (the paper has none)',
            positive_or_inf,
        ),
    )
    COMPENSATE: ClassVar[bool] = True

    def __init__(
        self,
        input_gain: float,
        sample_period: float,
        omega_c: float = 12.0,
        zeta_c: float = 0.7071,
        torque_limit: float = DEFAULT_TORQUE_LIMIT,
    ) -> None:
        b = float(input_gain)
        if not math.isfinite(b) or b == 0.0:
            raise ParameterError('input_gain', input_gain, 'must be finite and non-zero')
        reason = positive(sample_period)
        if reason:
            raise ParameterError('sample_period', sample_period, reason)
        values = validate_all(
            self.PARAMETERS,
            {'omega_c': omega_c, 'zeta_c': zeta_c, 'torque_limit': torque_limit},
            prefix=self.PREFIX + '.',
        )
        if values['omega_c'] == 0.0:
            raise ParameterError('pd.omega_c', 0.0, 'the tuning rule is resolved by the node')
        self._b = b
        self._T = float(sample_period)  # unused by the continuous law; kept for the node
        self._omega_c: float = values['omega_c']
        self._zeta_c: float = values['zeta_c']
        self._limit: float = values['torque_limit']
        # Beltrán 2013 eq. (11)-(12), misprint fixed: p_d(s) = s² + 2 ζ_c ω_c s + ω_c²
        self._alpha1 = 2.0 * self._zeta_c * self._omega_c
        self._alpha0 = self._omega_c * self._omega_c

    @classmethod
    def from_parameters(
        cls, input_gain: float, sample_period: float, values: Mapping[str, Any]
    ) -> _PdLaw:
        """Build from a mapping keyed by PARAMETERS names (missing names take defaults)."""
        v = validate_all(cls.PARAMETERS, values, prefix=cls.PREFIX + '.')
        return cls(input_gain, sample_period, **v)

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
        read = (t, y, ref.position, ref.velocity, ref.acceleration, est.velocity, xi_hat)
        if not all(math.isfinite(v) for v in read):
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


class PdController(_PdLaw):
    """Eq. (9) with ξ̂ ≡ 0 (paper figs. 5-7); still uses the observer's velocity."""

    COMPENSATE: ClassVar[bool] = False
