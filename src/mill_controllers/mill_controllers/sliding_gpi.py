"""Sliding-mode GPI controller, Chávez-Conde eq. (13)-(17) (ROS-free).

Same plant reading, reconstructor and discretisation as gpi_controller (read its
docstring): F̂ = b∫τ − κ(F − F(0)) with the applied torque integrated exactly under the
zero-order hold, forward-rectangle error integral, elapsed time from t.

The law. Expanding μσ̂ in eq. (17) with σ̂ of eq. (13),

    v = F̈* − (α1 + μ)(F̂ − Ḟ*) − (α0 + μα1) e − μα0 ∫e − μγ sign(σ̂),

i.e. a GPI law whose error polynomial is (s² + α1 s + α0)(s + μ), α1 = 2ζω_n, α0 = ω_n²
(paper: ζ = 0.9, ω_n = 80, μ = 15), plus the switching term −μγ sign(σ̂). The linear part
runs the gains of gpi_controller for those three roots: the discrete pole-mapped ones
(discretisation 'zoh': exact roots z = exp(sT) of the sampled loop when γ = 0) or the
expanded continuous ones ('continuous'); σ̂ is eq. (13) as printed,
σ̂ = (F̂ − Ḟ*) + α1 e + α0 ∫e, with the continuous α1, α0 and the same ∫e.

sign/sat: with boundary_layer φ = 0 (default, the paper) the switching term is the exact
signum, sign(0) = 0. Sampled at T it cannot slide ideally: it chatters, every sample
flipping ẍ by up to 2μγ (or the torque limit), a band of about μγT in σ̂ (0.15 m/s for
the paper's values) unless the torque limit cuts it. φ > 0 replaces sign(σ̂) by
sat(σ̂/φ) (a boundary layer, continuous): no chattering when φ ≳ μγT/(2 − μT) (the
switching term is then a linear gain μγ/φ that the sampled loop keeps stable), at the
price of a residual σ̂ of order φ·(disturbance)/(μγ).

Units: σ̂ is a velocity [m/s], so γ is in m/s and μγ in m/s²; the paper's γ = 10 read
literally asks for ±150 m/s² (±472 N·m on the Chávez-Conde x axis), far above any torque
limit: with a finite limit the switching term saturates the actuator.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, ClassVar

from mill_common.parameters import ParamSpec, non_negative, positive, validate_all
from mill_common.signals import ControlInputs

from mill_controllers.gpi_controller import (
    DAMPING_RATE_SPEC,
    DISCRETISATION_SPEC,
    TORQUE_LIMIT_SPEC,
    GpiController,
)
from mill_controllers.pd_law import DEFAULT_TORQUE_LIMIT


class SlidingGpiController(GpiController):
    """Chávez-Conde eq. (17) for one axis: GPI law plus −μγ sign(σ̂)."""

    PREFIX: ClassVar[str] = 'sliding_gpi'
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec(
            'omega_n',
            80.0,
            'natural frequency ω_n of the sliding dynamics eq. (15), α0 = ω_n² [rad/s]',
            positive,
        ),
        ParamSpec('zeta', 0.9, 'damping ratio ζ of eq. (15), α1 = 2ζω_n [-]', positive),
        ParamSpec('mu', 15.0, 'μ of the reaching law eq. (16) [1/s]', positive),
        ParamSpec('gamma', 10.0, 'γ of the reaching law eq. (16) [m/s]', non_negative),
        ParamSpec(
            'boundary_layer',
            0.0,
            'φ: sign(σ̂) is replaced by sat(σ̂/φ); 0 = the exact signum (paper) [m/s]',
            non_negative,
        ),
        DAMPING_RATE_SPEC,
        DISCRETISATION_SPEC,
        TORQUE_LIMIT_SPEC,
    )

    def __init__(
        self,
        input_gain: float,
        sample_period: float,
        omega_n: float = 80.0,
        zeta: float = 0.9,
        mu: float = 15.0,
        gamma: float = 10.0,
        boundary_layer: float = 0.0,
        damping_rate: float = 0.0,
        discretisation: str = 'zoh',
        torque_limit: float = DEFAULT_TORQUE_LIMIT,
    ) -> None:
        # The GPI part with the real root at −μ: (s² + α1 s + α0)(s + μ).
        super().__init__(
            input_gain,
            sample_period,
            omega_n=omega_n,
            zeta=zeta,
            pole=mu,
            damping_rate=damping_rate,
            discretisation=discretisation,
            torque_limit=torque_limit,
        )
        values = validate_all(
            self.PARAMETERS,
            {
                'omega_n': omega_n,
                'zeta': zeta,
                'mu': mu,
                'gamma': gamma,
                'boundary_layer': boundary_layer,
                'damping_rate': damping_rate,
                'discretisation': discretisation,
                'torque_limit': torque_limit,
            },
            prefix=self.PREFIX + '.',
        )
        self._mu: float = values['mu']
        self._gamma: float = values['gamma']
        self._phi: float = values['boundary_layer']
        # Chávez-Conde section 5: α1 = 2ζω_n, α0 = ω_n² (the surface eq. (13)-(15))
        self._a1 = 2.0 * self._zeta * self._omega_n
        self._a0 = self._omega_n**2
        self._sigma = 0.0

    @classmethod
    def from_parameters(
        cls, input_gain: float, sample_period: float, values: Mapping[str, Any]
    ) -> SlidingGpiController:
        v = validate_all(cls.PARAMETERS, values, prefix=cls.PREFIX + '.')
        return cls(input_gain, sample_period, **v)

    @property
    def surface_gains(self) -> tuple[float, float]:
        """(α0, α1) of the surface eq. (13) and of s² + α1 s + α0 eq. (15)."""
        return self._a0, self._a1

    @property
    def sigma(self) -> float:
        """σ̂ of the last compute(), eq. (13) [m/s]."""
        return self._sigma

    def switch(self, sigma: float) -> float:
        """sign(σ̂) (φ = 0, sign(0) = 0) or sat(σ̂/φ) (φ > 0)."""
        if self._phi > 0.0:
            return min(1.0, max(-1.0, sigma / self._phi))
        return 0.0 if sigma == 0.0 else math.copysign(1.0, sigma)

    def compute(self, inputs: ControlInputs) -> float:
        """Torque [N·m] at time t from the measured position y; the estimate is not used."""
        ref = inputs.reference
        e, de_hat, int_e = self._advance(inputs.t, inputs.position, ref)
        # Chávez-Conde eq. (13): σ̂ = (F̂ − Ḟ*) + α1 (F − F*) + α0 ∫(F − F*)
        self._sigma = de_hat + self._a1 * e + self._a0 * int_e
        k0, k1, k2 = self._k
        # Chávez-Conde eq. (17): v = F̈* − α1(F̂ − Ḟ*) − α0 e − μ[σ̂ + γ sign σ̂], the linear
        # part expanded to the cubic (s² + α1 s + α0)(s + μ) with discrete gains k
        v = ref.acceleration - k2 * de_hat - k1 * e - k0 * int_e
        v -= self._mu * self._gamma * self.switch(self._sigma)
        # eq. (17): u = d1 v + d2 F̂, i.e. b u = v + κ F̂
        return self._finish(v + self._kappa * self._f_hat)
