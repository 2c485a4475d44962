"""The RLS estimator of Hatwesh 2013 eq. (10)-(13) as an observer node's core (ROS-free).

For a controller that wants model estimates from outside (or for monitoring a drive's
dynamics while another law runs): each sample the velocity v(k) = (y(k) − y(k−1))/T and
the command u(k) update y(k) = a y(k−1) + Σ b_i u(k−i) (mill_models.rls), and
`status()` gives the FOPDT read-out K, τ, θ_d with the RLS diagnostics; the observer node
publishes it on /mill/<axis>/observer_state every sample.

Estimate: position y, velocity v(k) (the backward difference, as the Hatwesh loops use),
disturbance 0 (this observer estimates a model, not a disturbance); `model_estimate()`: the
FOPDT read-out from the samples before k. That is the model the adaptive PI designs with at
sample k, so `adaptive_pi.model_source: observer` with this observer computes the same
commands as the adaptive PI with its own estimator (same RLS parameters).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from mill_common.signals import Estimate, FopdtEstimate
from mill_models.rls import RlsEstimator, RlsParams

from mill_observers.base import Observer


@dataclass(frozen=True)
class RlsObserverParams(RlsParams):
    """The estimator's parameters (mill_models.rls) under this observer's prefix."""

    PREFIX: ClassVar[str] = 'rls'


class RlsObserver(Observer):
    """Identifies the velocity loop's FOPDT model online; passes the measurement through."""

    PARAMS: ClassVar[type[RlsObserverParams]] = RlsObserverParams
    PROVIDES_MODEL: ClassVar[bool] = True  # model_estimate() (controllers may ask for it)

    def __init__(
        self,
        input_gain: float,
        sample_period: float,
        params: RlsObserverParams = RlsObserverParams(),
    ) -> None:
        del input_gain  # the model is identified, not assumed
        self._T = sample_period
        self.rls = RlsEstimator.from_params(sample_period, params)
        self._y: float | None = None
        self._v = 0.0

    def correct(self, y: float) -> Estimate:
        self._v = 0.0 if self._y is None else (y - self._y) / self._T
        self._y = y
        return Estimate(y, self._v, 0.0)

    def predict(self, u: float) -> None:
        self.rls.update(self._v, u)  # u(k) enters the regressor of the next samples

    def model_estimate(self) -> FopdtEstimate:
        return self.rls.fopdt()

    def status(self) -> dict[str, float]:
        out = self.model_estimate().as_status()
        out.update(self.rls.diagnostics())
        return out
