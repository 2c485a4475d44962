"""Self-tuning PI velocity loop of Hatwesh 2013 and the fixed "machine PI" (ROS-free).

Both regulate the table velocity v [m/s] with a voltage u [V] (Hatwesh eq. (1)-(3): the
amplifier input) by a PI with a backward-Euler integral and conditional integration
(anti-windup), clipped to ±limit:

    u(k) = K_p e(k) + I(k),   I(k) = I(k−1) + K_i T e(k),   e = v* − v.

A gain change moves u by ΔK_p·e(k) (small: the gains are re-tuned every sample). Neither
the incremental form u(k) = u(k−1) + K_p Δe + K_i T e (under saturation it loses the clipped
part of the proportional step) nor a bumpless transfer that loads I with (ΔK_p)·e is used:
with the pole-cancelling design any offset left in I decays only with the plant's τ (≈ 2 s).

Loop quantities:
    v* = ẋ_ref + k_x (x_ref − y)   (k_x = position_gain; 0 = pure velocity loop as in the paper).

v is the backward difference of the measured position (velocity_source 'difference') or
est.velocity ('estimate'). The difference is the mean velocity of the last sample, half a
sample late: it costs the machine PI 13° of phase margin (76° with a sampled velocity, 63°
with the difference; `python -m mill_analysis.hatwesh_margins`). The suite's plants
measure position only, so the Hatwesh scenarios use the difference (no velocity sensor).

AdaptivePi: an RlsEstimator (mill_models.rls) identifies y(k) = a y(k−1) + Σ b_i u(k−i)
from (v, u) each sample; from its FOPDT read-out K, τ, θ_d the PI is re-tuned by the
phase-margin rule (reading of Hatwesh eq. (7)-(8) and "PI controller design"; both rules in
mill_controllers.phase_margin, chosen by design_rule):

    K(s) = K_i (1 + τ s)/s      (eq. (8) with a = K_i, b = τ: the PI zero cancels the
                                 estimated plant pole, which fixes the one free parameter),
    'continuous' (default): L(s) = K_i K e^{−θs}/s, θ = θ_d + T/2 (the hold as a delay),
        ω_gc = (π/2 − φ_m)/θ,  K_i = ω_gc/K,  K_p = τ ω_gc/K;
    'discrete': the same conditions on the sampled loop L(z) = C(z) P(z), exactly.

Until the estimator has had `warmup` updates and gives a usable model (0 < a < 1, i.e.
0 < τ < ∞, and K > 0), the initial gains are used.

model_source 'observer': the law runs no estimator of its own and designs with inputs.model,
the FOPDT estimate of the observer node (observer `rls`, published on
/mill/<axis>/observer_state). The rls observer's estimate at sample k has used the same
samples as the internal one, so both sources give the same commands (a test checks this).

MachinePi: the fixed gains of Hatwesh Table 1, K_p = 1.5735, K_i = 5.4976 at 0.25 ms. The
paper does not state their velocity unit. On the x axis of Table 1 (K_a K_t = 21.87 N·m/V,
J = 2.8828e-3 kg·m², B = 1.4e-3 N·m·s) the sampled loop is stable with the error in motor
rev/s (crossover 1.9e3 rad/s, phase margin 76° with a sampled velocity, 63° with the
backward difference), and also in m/min or m/s of the table, but unstable in rad/s, rpm or mm/s
(crossover beyond what 0.25 ms sampling allows). Motor rev/s (= table mm/s ÷ 12 mm pitch) is
the default reading: a 300 Hz velocity-loop bandwidth, typical of such servo drives.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

from mill_common.declared import ParamSet, param
from mill_common.parameters import (
    ParameterError,
    ParamSpec,
    in_range,
    non_negative,
    one_of,
    positive,
    positive_int,
    positive_or_inf,
)
from mill_common.signals import AxisReference, ControlInputs, Estimate, FopdtEstimate
from mill_models.rls import RLS_PARAMETERS, RlsEstimator

from mill_controllers.base import AxisController, saturate
from mill_controllers.phase_margin import DESIGN_RULES, design_pi

# Hatwesh 2013 Table 1, x axis.
HATWESH_PITCH = 0.012  # ball-screw pitch [m]
HATWESH_KP = 1.5735
HATWESH_KI = 5.4976
DEFAULT_VOLTAGE_LIMIT = 10.0  # ±10 V analogue amplifier command

# Velocity units the machine PI's error may be expressed in: factor per (m/s) of table speed.
_UNITS = ('rev/s', 'm/min', 'm/s', 'rad/s', 'rpm', 'mm/s')


def unit_factor(unit: str, pitch: float) -> float:
    """How many `unit` one m/s of table velocity is (rev/s etc. are motor/screw speeds)."""
    return {
        'rev/s': 1.0 / pitch,
        'rad/s': 2.0 * math.pi / pitch,
        'rpm': 60.0 / pitch,
        'mm/s': 1000.0,
        'm/s': 1.0,
        'm/min': 60.0,
    }[unit]


def _shared(spec: ParamSpec) -> Any:
    """A field declared by a spec another package owns (mill_models.rls): same default,
    text, check and unit, so that the declaration stays in one place."""
    unit = f' [{spec.unit}]' if spec.unit else ''
    text = spec.description.removesuffix(unit) if unit else spec.description
    return param(spec.default, text, spec.check, unit=spec.unit, read_only=spec.read_only)


_RLS = {s.name: s for s in RLS_PARAMETERS}


@dataclass(frozen=True)
class VelocityPiParams(ParamSet):
    """What both velocity PIs take: the gains (the machine PI's Table 1 values), the outer
    position gain, the saturation and the velocity measurement."""

    k_p: float = param(
        HATWESH_KP, 'proportional gain K_p, Table 1 [V per velocity_unit]', non_negative
    )
    k_i: float = param(
        HATWESH_KI, 'integral gain K_i, Table 1 [V per velocity_unit·s]', non_negative
    )
    position_gain: float = param(
        0.0,
        'outer P position gain k_x, v* = ẋ_ref + k_x (x_ref − y); 0 = velocity loop only '
        '(the paper)',
        non_negative,
        unit='1/s',
    )
    voltage_limit: float = param(
        DEFAULT_VOLTAGE_LIMIT,
        'command saturation ±limit [V]; .inf disables it',
        positive_or_inf,
    )
    velocity_source: str = param(
        'difference',
        "measured velocity: 'difference' = (y(k) − y(k−1))/T, 'estimate' = est.velocity",
        one_of('difference', 'estimate'),
    )


@dataclass(frozen=True)
class MachinePiParams(VelocityPiParams):
    """Hatwesh 2013 Table 1 fixed PI and the unit its gains act in."""

    PREFIX: ClassVar[str] = 'machine_pi'
    velocity_unit: str = param(
        'rev/s',
        'unit of the velocity error the gains act on (not stated in the paper; rev/s of '
        'the motor keeps the 0.25 ms loop stable)',
        one_of(*_UNITS),
    )
    screw_pitch: float = param(HATWESH_PITCH, 'ball-screw pitch h_p, Table 1', positive, unit='m')


@dataclass(frozen=True)
class AdaptivePiParams(VelocityPiParams):
    """The self-tuning PI: initial gains, the phase-margin design and the RLS."""

    PREFIX: ClassVar[str] = 'adaptive_pi'
    k_p: float = param(
        HATWESH_KP / HATWESH_PITCH,
        'initial proportional gain until the estimate is usable (default: Table 1 read '
        'in motor rev/s)',
        non_negative,
        unit='V/(m/s)',
    )
    k_i: float = param(
        HATWESH_KI / HATWESH_PITCH,
        'initial integral gain until the estimate is usable',
        non_negative,
        unit='V/m',
    )
    phase_margin: float = param(
        60.0,
        'desired phase margin φ_m (the machine PI has ≈ 63-76° on the nominal plant)',
        in_range(1.0, 89.0),
        unit='deg',
    )
    design_rule: str = param(
        'continuous',
        "phase-margin rule: 'continuous' = ω_gc = (π/2 − φ_m)/θ with the hold as a T/2 "
        "delay (the paper's s-domain eq. (8)-(10)); 'discrete' = exact on the sampled loop",
        one_of(*DESIGN_RULES),
    )
    model_source: str = param(
        'internal',
        "plant model for the design: 'internal' = the law's own RLS (the parameters "
        "below), 'observer' = the FOPDT estimate of the observer node (observer: rls)",
        one_of('internal', 'observer'),
    )
    forgetting: float = _shared(_RLS['forgetting'])
    initial_covariance: float = _shared(_RLS['initial_covariance'])
    covariance_limit: float = _shared(_RLS['covariance_limit'])
    input_taps: int = _shared(_RLS['input_taps'])
    load_term: bool = _shared(_RLS['load_term'])
    # a field() with a default_factory, as param() makes for a list (ruff cannot tell)
    a_bounds: list[float] = _shared(_RLS['a_bounds'])  # noqa: RUF009
    b_bounds: list[float] = _shared(_RLS['b_bounds'])  # noqa: RUF009
    warmup: int = param(
        400,
        'RLS updates before the estimated gains replace the initial ones',
        positive_int,
        unit='samples',
    )


class _VelocityPi(AxisController):
    """Incremental PI on the table velocity; subclasses supply the gains."""

    PARAMS: ClassVar[type[VelocityPiParams]]
    OUTPUT_UNIT: ClassVar[str] = 'V'  # amplifier input voltage (Hatwesh eq. (1))

    def _init_loop(self, sample_period: float, params: VelocityPiParams) -> None:
        reason = positive(sample_period)
        if reason:
            raise ParameterError('sample_period', sample_period, reason)
        self._T = float(sample_period)
        self._kx = params.position_gain
        self._limit = params.voltage_limit
        self._use_estimate = params.velocity_source == 'estimate'
        self._y_prev: float | None = None
        self._i = 0.0
        self._u = 0.0
        self._v = 0.0

    def _measure(self, t: float, y: float, ref: AxisReference, est: Estimate) -> float:
        inputs = (t, y, ref.position, ref.velocity, est.velocity)
        if not all(math.isfinite(x) for x in inputs):
            raise ValueError(
                f'{type(self).__name__}: non-finite input (t={t!r}, y={y!r}, ref={ref!r}, '
                f'velocity estimate={est.velocity!r})'
            )
        if self._use_estimate:
            v = est.velocity
        else:
            v = 0.0 if self._y_prev is None else (y - self._y_prev) / self._T
        self._y_prev = y
        self._v = v
        return v

    def _pi_step(self, e: float, kp: float, ki: float) -> float:
        # PI: u(k) = K_p e(k) + I(k),  I(k) = I(k−1) + K_i T e(k)
        i_new = self._i + ki * self._T * e
        u = kp * e + i_new
        u_sat = saturate(u, self._limit)
        if u_sat == u or e * (u - u_sat) <= 0.0:  # conditional integration
            self._i = i_new
        self._u = u_sat
        return u_sat

    def _error(self, y: float, ref: AxisReference, v: float) -> float:
        return ref.velocity + self._kx * (ref.position - y) - v

    def reset(self) -> None:
        self._y_prev = None
        self._i = 0.0
        self._u = 0.0

    @property
    def velocity(self) -> float:
        """Last measured velocity [m/s]."""
        return self._v


class MachinePi(_VelocityPi):
    """Hatwesh 2013 Table 1 fixed PI; the error is converted to velocity_unit first."""

    PARAMS: ClassVar[type[MachinePiParams]] = MachinePiParams

    def __init__(
        self,
        input_gain: float,
        sample_period: float,
        params: MachinePiParams = MachinePiParams(),
    ) -> None:
        del input_gain  # voltage output
        self._init_loop(sample_period, params)
        self._factor = unit_factor(params.velocity_unit, params.screw_pitch)
        self._kp, self._ki = params.k_p, params.k_i

    @property
    def gains_si(self) -> tuple[float, float]:
        """(K_p [V/(m/s)], K_i [V/m]) after the unit conversion."""
        return self._kp * self._factor, self._ki * self._factor

    def compute(self, inputs: ControlInputs) -> float:
        """Voltage [V] from y [m], ref [m, m/s] (and est.velocity if selected)."""
        y, ref = inputs.position, inputs.reference
        v = self._measure(inputs.t, y, ref, inputs.estimate)
        e = self._error(y, ref, v) * self._factor  # error in velocity_unit
        return self._pi_step(e, self._kp, self._ki)


class AdaptivePi(_VelocityPi):
    """Hatwesh 2013 self-tuning PI: RLS on the velocity loop + phase-margin re-tuning."""

    PARAMS: ClassVar[type[AdaptivePiParams]] = AdaptivePiParams

    def __init__(
        self,
        input_gain: float,
        sample_period: float,
        params: AdaptivePiParams = AdaptivePiParams(),
    ) -> None:
        del input_gain  # voltage output; the plant is identified online
        self._init_loop(sample_period, params)
        self._kp0, self._ki0 = params.k_p, params.k_i
        self._kp, self._ki = self._kp0, self._ki0
        self._phi_m = math.radians(params.phase_margin)
        self._rule = params.design_rule
        self._warmup = params.warmup
        self._w_gc = math.nan
        self._adapted = False
        self._external = params.model_source == 'observer'
        self._model: FopdtEstimate | None = None  # the model of the current design
        self.rls = RlsEstimator.from_parameters(self._T, params.values())

    def compute(self, inputs: ControlInputs) -> float:
        """Voltage [V]; identifies the plant from (v(k), u(k)) and re-tunes every sample."""
        y, ref = inputs.position, inputs.reference
        v = self._measure(inputs.t, y, ref, inputs.estimate)
        if self._external:
            if inputs.model is None:
                raise ValueError(
                    'adaptive_pi.model_source is observer but no model estimate came with '
                    'the sample (the observer must be rls)'
                )
            self._model = inputs.model
        else:
            self._model = self.rls.fopdt()
        self._retune(self._model)
        u = self._pi_step(self._error(y, ref, v), self._kp, self._ki)
        if not self._external:
            self.rls.update(v, u)  # u(k) enters the regressor of the next samples
        return u

    def _retune(self, model: FopdtEstimate) -> None:
        if model.updates < self._warmup:
            return
        if not (0.0 < model.time_constant < math.inf and model.gain > 0.0):
            return  # no usable model (pole a = e^{−T/τ} outside (0, 1)): keep the last gains
        self._kp, self._ki, self._w_gc = design_pi(self._rule, model, self._phi_m, self._T)
        self._adapted = True

    def reset(self) -> None:
        super().reset()
        self.rls.reset()
        self._model = None
        self._kp, self._ki = self._kp0, self._ki0
        self._adapted = False
        self._w_gc = math.nan

    @property
    def needs_model(self) -> bool:
        """True if compute() needs inputs.model (model_source 'observer')."""
        return self._external

    # --- published state -------------------------------------------------------------

    @property
    def gains(self) -> tuple[float, float]:
        """Current (K_p [V/(m/s)], K_i [V/m])."""
        return self._kp, self._ki

    @property
    def adapted(self) -> bool:
        """True once the gains come from the estimate."""
        return self._adapted

    @property
    def crossover(self) -> float:
        """ω_gc of the current design [rad/s] (nan before adaptation)."""
        return self._w_gc

    def model(self) -> FopdtEstimate:
        """The FOPDT estimate of the last design: K [(m/s)/V], τ [s], θ_d [s]."""
        return self._model if self._model is not None else self.rls.fopdt()

    def status(self) -> dict[str, float]:
        """Everything worth publishing: estimates, gains, RLS diagnostics (own RLS only)."""
        m = self.model()
        out = {
            'k_p': self._kp,
            'k_i': self._ki,
            'crossover': self._w_gc,
            'adapted': 1.0 if self._adapted else 0.0,
            'gain': m.gain,
            'time_constant': m.time_constant,
            'dead_time': m.dead_time,
        }
        if self._external:
            out['updates'] = float(m.updates)
        else:
            out.update(self.rls.diagnostics())
        return out
