"""Linear extended-state observer with one bandwidth, for real machines (ROS-free).

The axis model is the GPI observer's, ẍ = b·τ + ξ, with ξ a Taylor polynomial of degree
`degree` (the GPI observer of Beltrán 2013 takes 4). Every error pole sits at −ω_o, the
bandwidth parametrization of linear active disturbance rejection (Gao 2003): one number
sets how fast the estimate follows, and a low degree keeps the estimate's overshoot small.
That overshoot decides how far the controller's input gain may be off: with degree 0 the
ADRC loop stays stable for a true gain from about 0.5 to 2 times the nominal one (a mass
from half to twice the model's), where the paper's degree 4 allows about 0.8 to 1.2
(docs/realtime.md, "Tuning for a rate and a delay").

`omega_o` 0 (the default) asks the node for the tuning rule's bandwidth at its sample
period and command delay (mill_models.loop_tuning). Sampled exactly, gains placed as the
GPI observer's (mill_observers.chain_design); a current estimator.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

from mill_common.parameters import (
    ParameterError,
    ParamSpec,
    check_gain_and_period,
    in_range,
    non_negative,
    validate_all,
)
from mill_common.signals import Estimate
from mill_models.loop_tuning import loop_tuning

from mill_observers.base import Observer
from mill_observers.chain_design import (
    ChainDesign,
    ChainObserver,
    advance,
)


def _degree(value: Any) -> str | None:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 4:
        return 'must be a whole number from 0 to 4'
    return None


class ExtendedStateObserver(ChainObserver, Observer):
    PREFIX: ClassVar[str] = 'eso'
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec(
            'omega_o',
            0.0,
            'observer bandwidth ω_o: every error pole at −ω_o [rad/s]; 0 = the tuning rule '
            'for the sample period and command delay',
            non_negative,
        ),
        ParamSpec(
            'degree',
            0,
            'degree of the disturbance model: 0 a constant, 1 a ramp, … 4 (as the GPI '
            'observer); higher follows faster changes, lower tolerates a wrong input gain',
            _degree,
        ),
        ParamSpec(
            'bandwidth_factor',
            1.0,
            'with omega_o 0: the tuning rule bandwidth times this factor [-]',
            in_range(0.05, 4.0),
        ),
    )

    def __init__(
        self, input_gain: float, sample_period: float, omega_o: float, degree: int = 0
    ) -> None:
        self._b, self._T = check_gain_and_period(input_gain, sample_period)
        if not (math.isfinite(omega_o) and omega_o > 0.0):
            raise ParameterError('eso.omega_o', omega_o, 'must be > 0 when the observer is built')
        self.omega_o = float(omega_o)
        self.degree = int(degree)
        n = self._n = self.degree + 3
        design = ChainDesign(n, self._b, self._T, [complex(-self.omega_o, 0.0)] * n)
        self._scale = design.scale
        self._m = [float(v) for v in design.m_s]
        # the input column of the sampled model: b·T²·[½, 1, 0, …]
        self._g0, self._g1 = float(design.bd_s[0]), float(design.bd_s[1])
        self._z = [0.0] * n
        self._initialised = False

    @classmethod
    def from_parameters(
        cls, input_gain: float, sample_period: float, values: Mapping[str, Any]
    ) -> ExtendedStateObserver:
        v = validate_all(cls.PARAMETERS, values, prefix=cls.PREFIX + '.')
        omega_o = v['omega_o']
        if omega_o == 0.0:  # the rule; the node asks it for its own delay (config.py)
            omega_o = loop_tuning(sample_period, 0).omega_o * v['bandwidth_factor']
        return cls(input_gain, sample_period, omega_o, v['degree'])

    def correct(self, y: float) -> Estimate:
        if not math.isfinite(y):
            raise ValueError(f'eso: measured position is not finite: {y!r}')
        z = self._z
        if not self._initialised:
            z[:] = [float(y)] + [0.0] * (self._n - 1)
            self._initialised = True
        else:
            r = y - z[0]
            for i, m in enumerate(self._m):
                z[i] += m * r
        return self._estimate(z)

    def _estimate(self, z: Sequence[float]) -> Estimate:
        T = self._T
        return Estimate(z[0], z[1] / T, z[2] / (T * T))

    def _advanced(self, z: list[float], u: float, periods: float = 1.0) -> list[float]:
        return advance(z, self._g0, self._g1, u, periods)

    def predict(self, u: float) -> None:
        if not self._initialised:
            raise RuntimeError('eso: predict called before the first correct()')
        if not math.isfinite(u):
            raise ValueError(f'eso: command is not finite: {u!r}')
        self._z = self._advanced(self._z, u)

    def predicted(self, inputs: Sequence[float]) -> Estimate:
        z = self._z
        for u in inputs:
            z = self._advanced(z, u)
        return self._estimate(z)

    def reset(self) -> None:
        self._z = [0.0] * self._n
        self._initialised = False
