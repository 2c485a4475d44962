"""Combined IMBDO + DFO of Maharof 2018 §4.4 (ROS-free).

Fig. 8 is not in the text; §1 says the DFO "explicitly estimates the cutting force while
IMBDO estimates remaining discrepancies". Reading used here (a cascade, no algebraic loop):

- the DFO runs on the applied voltage u and the position y, as alone (d̂_D = Σ q̂1_i);
- the IMBDO treats d̂_D as a known part of the input, i.e. it is fed u + d̂_D, so it
  estimates only the remainder d − d̂_D: d̂_I = Q·[G_n⁻¹ y − (u + d̂_D)];
- the compensation is d̂ = d̂_D + d̂_I [V] (subtract it from u, same convention as both).

Equivalently d̂ = (1 − Q)·d̂_D + Q·[G_n⁻¹ y − u]: the IMBDO dominates inside the Q band
and removes any DC bias of the DFO; the DFO adds its harmonics where |1 − Q| > 0. Both keep
their own gains, as in the paper. Estimate.velocity is the backward difference of y
(both parts return the same one).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from mill_common.signals import Estimate

from mill_observers.base import Observer
from mill_observers.dfo import Dfo, DfoParams
from mill_observers.imbdo import Imbdo, ImbdoParams


@dataclass(frozen=True)
class ImbdoDfoParams(DfoParams, ImbdoParams):
    """Both observers' parameters, one nominal model: the plant's, the IMBDO's, the DFO's."""

    PREFIX: ClassVar[str] = 'imbdo_dfo'


class ImbdoDfo(Observer):
    """Maharof 2018 combined observer; disturbance = d̂_D + d̂_I [V] (subtract it from u)."""

    PARAMS: ClassVar[type[ImbdoDfoParams]] = ImbdoDfoParams
    DISTURBANCE_UNIT: ClassVar[str] = 'V'  # input-equivalent voltage

    def __init__(
        self, input_gain: float, sample_period: float, params: ImbdoDfoParams = ImbdoDfoParams()
    ) -> None:
        # the set is both an ImbdoParams and a DfoParams: each part reads its own fields
        self._imbdo = Imbdo(input_gain, sample_period, params)
        self._dfo = Dfo(input_gain, sample_period, params)
        self._d_dfo = 0.0
        self._d_imbdo = 0.0

    def correct(self, y: float) -> Estimate:
        """Measurement update with y [m]; Estimate(y [m], Δy/T [m/s], d̂_D + d̂_I [V])."""
        if not math.isfinite(y):
            raise ValueError(f'ImbdoDfo.correct: measured position is not finite: {y!r}')
        est_d = self._dfo.correct(y)
        est_i = self._imbdo.correct(y)
        self._d_dfo = est_d.disturbance
        self._d_imbdo = est_i.disturbance
        return Estimate(float(y), est_d.velocity, self._d_dfo + self._d_imbdo)

    def predict(self, u: float) -> None:
        """Time update with the applied voltage u [V]; the IMBDO is fed u + d̂_D."""
        if not math.isfinite(u):
            raise ValueError(f'ImbdoDfo.predict: command is not finite: {u!r}')
        self._dfo.predict(u)
        self._imbdo.predict(u + self._d_dfo)

    def reset(self) -> None:
        self._dfo.reset()
        self._imbdo.reset()
        self._d_dfo = self._d_imbdo = 0.0

    def set_spindle_speed(self, spindle_speed: float) -> None:
        """Re-tune the DFO resonators to a new spindle speed [rpm]."""
        self._dfo.set_spindle_speed(spindle_speed)

    @property
    def initialised(self) -> bool:
        return self._dfo.initialised

    @property
    def parts(self) -> tuple[float, float]:
        """(d̂_D, d̂_I) of the last correct() [V]."""
        return self._d_dfo, self._d_imbdo

    @property
    def imbdo(self) -> Imbdo:
        return self._imbdo

    @property
    def dfo(self) -> Dfo:
        return self._dfo
