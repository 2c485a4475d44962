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
period and command delay (mill_models.loop_tuning), times `bandwidth_factor`
(EsoParams.tuned); an observer built alone takes the rule without delay. Sampled exactly,
gains placed as the GPI observer's (mill_observers.chain_design); a current estimator.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, TypeVar

from mill_common.declared import ParamSet, param
from mill_common.parameters import check_gain_and_period, in_range, non_negative
from mill_common.signals import Estimate
from mill_models.loop_tuning import loop_tuning

from mill_observers.base import Observer
from mill_observers.chain_design import (
    ChainDesign,
    ChainObserver,
    advance,
)

E = TypeVar('E', bound='EsoParams')


def _degree(value: Any) -> str | None:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 4:
        return 'must be a whole number from 0 to 4'
    return None


@dataclass(frozen=True)
class EsoParams(ParamSet):
    """The bandwidth and the disturbance model's degree."""

    PREFIX: ClassVar[str] = 'eso'
    omega_o: float = param(
        0.0,
        'observer bandwidth ω_o: every error pole at −ω_o',
        non_negative,
        unit='rad/s',
        rule='omega_o',
    )
    degree: int = param(
        0,
        'degree of the disturbance model: 0 a constant, 1 a ramp, … 4 (as the GPI '
        'observer); higher follows faster changes, lower tolerates a wrong input gain',
        _degree,
    )
    bandwidth_factor: float = param(
        1.0,
        'with omega_o 0: the tuning rule bandwidth times this factor',
        in_range(0.05, 4.0),
        unit='-',
    )

    def tuned(self: E, rule: Mapping[str, float]) -> E:
        """The rule's bandwidth times bandwidth_factor where omega_o is 0."""
        return super().tuned({**rule, 'omega_o': rule['omega_o'] * self.bandwidth_factor})


class ExtendedStateObserver(ChainObserver, Observer):
    PARAMS: ClassVar[type[EsoParams]] = EsoParams

    def __init__(
        self, input_gain: float, sample_period: float, params: EsoParams = EsoParams()
    ) -> None:
        self._b, self._T = check_gain_and_period(input_gain, sample_period)
        if params.omega_o == 0.0:  # the rule; the node asks it for its own delay (config.py)
            rule = loop_tuning(self._T, 0)
            params = params.tuned({'omega_c': rule.omega_c, 'omega_o': rule.omega_o})
        self.omega_o = params.omega_o
        self.degree = params.degree
        n = self._n = self.degree + 3
        design = ChainDesign(n, self._b, self._T, [complex(-self.omega_o, 0.0)] * n)
        self._scale = design.scale
        self._m = [float(v) for v in design.m_s]
        # the input column of the sampled model: b·T²·[½, 1, 0, …]
        self._g0, self._g1 = float(design.bd_s[0]), float(design.bd_s[1])
        self._z = [0.0] * n
        self._initialised = False

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
