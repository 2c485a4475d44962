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
from dataclasses import dataclass
from typing import ClassVar

from mill_common.declared import param
from mill_common.parameters import non_negative, positive
from mill_common.signals import ControlInputs

from mill_controllers.gpi_controller import GpiController, GpiParams, GpiShared


@dataclass(frozen=True)
class SlidingGpiParams(GpiShared):
    """The sliding GPI law's parameters: the surface eq. (13)-(15) and the reaching law."""

    PREFIX: ClassVar[str] = 'sliding_gpi'
    omega_n: float = param(
        80.0,
        'natural frequency ω_n of the sliding dynamics eq. (15), α0 = ω_n²',
        positive,
        unit='rad/s',
    )
    zeta: float = param(0.9, 'damping ratio ζ of eq. (15), α1 = 2ζω_n', positive, unit='-')
    mu: float = param(15.0, 'μ of the reaching law eq. (16)', positive, unit='1/s')
    gamma: float = param(10.0, 'γ of the reaching law eq. (16)', non_negative, unit='m/s')
    boundary_layer: float = param(
        0.0,
        'φ: sign(σ̂) is replaced by sat(σ̂/φ); 0 = the exact signum (paper)',
        non_negative,
        unit='m/s',
    )


class SlidingGpiController(GpiController):
    """Chávez-Conde eq. (17) for one axis: GPI law plus −μγ sign(σ̂)."""

    PARAMS: ClassVar[type[GpiShared]] = SlidingGpiParams

    def __init__(
        self,
        input_gain: float,
        sample_period: float,
        params: SlidingGpiParams = SlidingGpiParams(),
    ) -> None:
        # The GPI part with the real root at −μ: (s² + α1 s + α0)(s + μ).
        gpi = GpiParams(
            omega_n=params.omega_n,
            zeta=params.zeta,
            pole=params.mu,
            damping_rate=params.damping_rate,
            discretisation=params.discretisation,
            torque_limit=params.torque_limit,
        )
        super().__init__(input_gain, sample_period, gpi)
        self._mu = params.mu
        self._gamma = params.gamma
        self._phi = params.boundary_layer
        # Chávez-Conde section 5: α1 = 2ζω_n, α0 = ω_n² (the surface eq. (13)-(15))
        self._a1 = 2.0 * self._zeta * self._omega_n
        self._a0 = self._omega_n**2
        self._sigma = 0.0

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
