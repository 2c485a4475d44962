"""Model-reference pole-placement force control of Rubio 2013 eq. (7)-(11) (ROS-free).

Design, for a hold β (polynomials in z, highest power first):

- plant H_β(z) = B(z)/A(z): the unit-gain force process 1/((τ_c s + 1)(τ_m s + 1))
  discretised under the β-FROH (mill_models.holds); the process gain K_p(a_dc) scales B and is
  applied at run time (S and T are divided by K_p; R does not depend on it);
- reference model eq. (7) G_m(s) = ω_n²/(s² + 2ξω_n s + ω_n²) with ξ = 0.7 and
  ω_n = 2.5/T_r, T_r = 3 spindle periods = 3T (§2.3, §5: ω_n ≈ 9.93 rad/s at 715 rpm;
  mill_models.reference_model), discretised with the same β-FROH:
  H_m,β(z) = B_m(z)/A_m(z), deg A_m = deg A = n;
- B = B⁺·B⁻: B⁺ (monic) holds the zeros inside `zero_cancel_radius` (1 = every stable
  zero, the paper's reading), B⁻ the rest and the leading coefficient; R = B⁺·R₁ (the
  papers README: eq. (10) prints R = B·R₁);
- observer polynomial A_o(z) = (z − e^{−T/τ_o})^{n_o}, our choice (the paper gives no
  values): by default n_o = 1 and τ_o = τ_c, an observer as fast as the fastest plant
  pole (e^{−T/τ_c} = e^{−4} ≈ 0.018, nearly deadbeat);
- eq. (10): A·R₁ + B⁻·S = z^{deg B⁻}·A_m·A_o, solved with the Sylvester matrix of A and
  B⁻ (deg S = n − 1, deg R₁ = deg B⁻ + n_o; mill_models.polynomials), so
  A·R + B·S = B⁺·z^{deg B⁻}·A_m·A_o;
- T = A_o·B_m/B⁻(1), so the closed loop B·T/(A·R + B·S) = B_m/A_m when every zero is
  cancelled (the case for the paper's plant at every β ∈ [−1, 1]); otherwise the model
  is B⁻(z)/(B⁻(1) z^{deg B⁻})·B_m/A_m (unit DC gain, the unstable zeros kept, causal).

The paper's eq. (9) degrees (deg R = n, deg A_m A_o = 2n) are those of a design without
cancellation and do not fit R = B⁺·R₁; the degrees above are the minimal causal ones:
deg R = n − 1 + n_o = deg T ≥ deg S.

Control law eq. (11): R(q)·f_c = T(q)·F_r − S(q)·F_p, computed as a causal difference
equation (u_k uses r_j, y_j for j ≤ k and u_j for j < k).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar, TypeVar

import numpy as np
from mill_common.declared import Configured, ParamSet, param
from mill_common.parameters import in_range, non_negative, positive
from mill_models.force_process import AffineLti, ForceProcessModel
from mill_models.holds import DiscreteTF, froh_discretize
from mill_models.polynomials import Poly, degree, pad, solve_diophantine, split_numerator, trim
from mill_models.reference_model import (
    natural_frequency as rise_time_frequency,  # the __init__ argument shadows the name
)
from mill_models.reference_model import reference_model, reference_state_space

# --- design -----------------------------------------------------------------------------


@dataclass(frozen=True)
class RstDesign:
    """R, S, T of eq. (10)-(11) for one hold β, on the unit-gain plant.

    r, s, t have the same length deg R + 1 (left-padded), r[0] = 1.
    """

    beta: float
    r: np.ndarray
    s: np.ndarray
    t: np.ndarray
    plant: DiscreteTF
    reference: DiscreteTF
    observer: np.ndarray
    b_plus: np.ndarray
    b_minus: np.ndarray
    r1: np.ndarray
    model_poles: np.ndarray = field(repr=False)  # z^{deg B⁻}·A_m

    @property
    def order(self) -> int:
        return len(self.r) - 1

    def characteristic_polynomial(self) -> np.ndarray:
        """A·R + B·S computed from the design (unit gain)."""
        return np.polyadd(np.polymul(self.plant.den, self.r), np.polymul(self.plant.num, self.s))

    def designed_polynomial(self) -> np.ndarray:
        """B⁺·z^{deg B⁻}·A_m·A_o: what A·R + B·S must equal."""
        return np.polymul(self.b_plus, np.polymul(self.model_poles, self.observer))


def design_rst(
    plant: DiscreteTF,
    reference: DiscreteTF,
    observer: Poly,
    zero_cancel_radius: float = 1.0,
) -> RstDesign:
    """Model-following R, S, T (module docstring) for a strictly proper plant."""
    a = trim(plant.den)
    b = trim(plant.num)
    n = len(a) - 1
    if len(b) - 1 >= n:
        raise ValueError('the plant must be strictly proper')
    am = trim(reference.den)
    bm = trim(reference.num)
    if len(am) - 1 != n:
        raise ValueError(f'reference model order {len(am) - 1} differs from the plant order {n}')
    ao = trim(observer)
    b_plus, b_minus = split_numerator(b, zero_cancel_radius)
    m_minus = len(b_minus) - 1
    model_poles = np.polymul(np.concatenate([[1.0], np.zeros(m_minus)]), am)
    # Rubio 2013 eq. (10): A R₁ + B⁻ S = A_m A_o (A_m extended by z^{deg B⁻})
    r1, s = solve_diophantine(a, b_minus, np.polymul(model_poles, ao))
    # R = B⁺ R₁ (papers README: printed R = B R₁)
    r = np.polymul(b_plus, r1)
    # T = A_o B_m / B⁻(1): closed loop B⁻(z)/(B⁻(1) z^{deg B⁻}) · B_m/A_m
    t = np.polymul(ao, bm) / np.polyval(b_minus, 1.0)
    d = len(r) - 1
    if degree(s) > d or degree(t) > d:
        raise ValueError('non-causal design: deg S or deg T exceeds deg R')
    lead = r[0]
    return RstDesign(
        beta=plant.beta,
        r=r / lead,
        s=pad(s, d + 1) / lead,
        t=pad(t, d + 1) / lead,
        plant=plant,
        reference=reference,
        observer=ao,
        b_plus=b_plus,
        b_minus=b_minus,
        r1=r1,
        model_poles=model_poles,
    )


def _observer_degree(value: Any) -> str | None:
    if not isinstance(value, int) or isinstance(value, bool) or not 0 <= value <= 6:
        return 'must be a whole number in [0, 6]'
    return None


@dataclass(frozen=True)
class RstDesignParams(ParamSet):
    """The eq. (7)-(11) design: reference model, observer polynomial, cancelled zeros."""

    damping_ratio: float = param(0.7, 'ξ of the reference model eq. (7)', positive, unit='-')
    rise_time_periods: float = param(
        3.0,
        'rise time T_r of the reference model in spindle periods (ω_n = 2.5/T_r)',
        positive,
        unit='-',
    )
    natural_frequency: float = param(
        0.0,
        'ω_n of eq. (7) [rad/s]; 0 = 2.5/T_r (Rubio 2013 §2.3)',
        non_negative,
    )
    observer_degree: int = param(
        1,
        'degree n_o of the observer polynomial A_o = (z − e^{−T/τ_o})^{n_o}',
        _observer_degree,
        unit='-',
    )
    observer_time_constant: float = param(
        0.0,
        'τ_o of the observer poles [s]; 0 = τ_c, the cutting-process constant',
        non_negative,
    )
    zero_cancel_radius: float = param(
        1.0,
        'plant zeros with |z| below this are cancelled (B⁺); the rest kept (B⁻)',
        in_range(0.0, 1.0),
        unit='-',
    )


@dataclass(frozen=True)
class ForceControlParams(RstDesignParams):
    """The basic scheme: the design and its one β."""

    PREFIX: ClassVar[str] = 'force_control'
    beta: float = param(0.0, 'β of the fractional-order hold, 0 = ZOH', in_range(-1, 1), unit='-')


L = TypeVar('L', bound='ForceLawBase')


class ForceLawBase(Configured):
    """A force law the force_controller parameter chooses: built as
    `Law(model, params, feed_min, feed_max)`, params its PARAMS set."""

    PARAMS: ClassVar[type[RstDesignParams]]

    @classmethod
    def from_parameters(
        cls: type[L],
        model: ForceProcessModel,
        values: Mapping[str, Any],
        feed_min: float = -math.inf,
        feed_max: float = math.inf,
    ) -> L:
        """The law from its values (names without prefix) and the feed range [mm/s]."""
        params = cls.PARAMS.from_values(values)
        return cls(model, params, feed_min, feed_max)  # type: ignore[call-arg]


class ForceControlDesigner:
    """Builds (and caches) the eq. (7)-(11) design for any β for one force-process model."""

    def __init__(
        self, model: ForceProcessModel, params: RstDesignParams = RstDesignParams()
    ) -> None:
        v = params
        self.model = model
        self.T = model.sample_period
        self.damping = v.damping_ratio
        rise_time = v.rise_time_periods * self.T
        wn = v.natural_frequency
        self.omega_n: float = wn if wn > 0 else rise_time_frequency(rise_time)
        tau_o = v.observer_time_constant or model.tau_c
        self.observer_pole = math.exp(-self.T / tau_o)
        self.observer = np.real(np.poly(np.full(v.observer_degree, self.observer_pole)))
        self.observer = np.atleast_1d(self.observer)
        self.zero_cancel_radius = v.zero_cancel_radius
        self._plant_s = model.unit_transfer_function()
        self._ref_s = reference_model(self.damping, self.omega_n)
        a, b, c = reference_state_space(self.damping, self.omega_n)
        self.reference_lti = AffineLti(a, b, c)
        self._cache: dict[float, RstDesign] = {}

    def design(self, beta: float) -> RstDesign:
        key = float(beta)
        d = self._cache.get(key)
        if d is None:
            plant = froh_discretize(self._plant_s, self.T, key)
            ref = froh_discretize(self._ref_s, self.T, key)
            d = design_rst(plant, ref, self.observer, self.zero_cancel_radius)
            if len(self._cache) > 512:
                self._cache.clear()
            self._cache[key] = d
        return d


# --- run time ---------------------------------------------------------------------------


class RstController:
    """Causal R(q)u = T(q)r − S(q)y with a process gain, polynomials swappable.

    The history (past r, y and applied u) is kept apart from the polynomials, so a
    multi-model supervisor can switch designs without losing it.
    """

    HISTORY: ClassVar[int] = 16

    def __init__(self, design: RstDesign, gain: float = 1.0) -> None:
        self._design = design
        self.set_gain(gain)
        self._r_hist = [0.0] * self.HISTORY  # r_{k−1}, r_{k−2}, …
        self._y_hist = [0.0] * self.HISTORY
        self._u_hist = [0.0] * self.HISTORY

    @property
    def design(self) -> RstDesign:
        return self._design

    def set_design(self, design: RstDesign) -> None:
        if design.order >= self.HISTORY:
            raise ValueError(f'controller order {design.order} exceeds the history length')
        self._design = design

    @property
    def gain(self) -> float:
        return self._gain

    def set_gain(self, gain: float) -> None:
        """Process gain K_p [N·s/mm] the unit-gain design is scaled by (S/K_p, T/K_p)."""
        if not (math.isfinite(gain) and gain > 0.0):
            raise ValueError(f'process gain must be finite and > 0, got {gain!r}')
        self._gain = float(gain)

    def update(self, reference: float, measured: float) -> float:
        """u_k from r_k, y_k and the past; raises ValueError on non-finite input."""
        if not (math.isfinite(reference) and math.isfinite(measured)):
            raise ValueError(
                f'RstController.update: non-finite input r={reference!r}, y={measured!r}'
            )
        d = self._design
        r_now = [reference, *self._r_hist]
        y_now = [measured, *self._y_hist]
        acc = 0.0
        for i in range(d.order + 1):
            acc += d.t[i] * r_now[i] - d.s[i] * y_now[i]
        # Rubio 2013 eq. (11): R(q) f_c = T(q) F_r − S(q) F_p, R monic
        u = acc / self._gain
        for i in range(1, d.order + 1):
            u -= d.r[i] * self._u_hist[i - 1]
        self._r_hist = r_now[: self.HISTORY]
        self._y_hist = y_now[: self.HISTORY]
        self._u_hist = [u, *self._u_hist[: self.HISTORY - 1]]
        return u

    def record_applied(self, u: float) -> None:
        """Replace the last output by what was actually applied (e.g. after clamping)."""
        if not math.isfinite(u):
            raise ValueError(f'applied feed must be finite, got {u!r}')
        self._u_hist[0] = float(u)

    @property
    def last_output(self) -> float:
        return self._u_hist[0]

    def history(self) -> tuple[list[float], list[float], list[float]]:
        """(past r, past y, past u), most recent first (copies)."""
        return list(self._r_hist), list(self._y_hist), list(self._u_hist)

    def load_history(self, history: tuple[list[float], list[float], list[float]]) -> None:
        r, y, u = history
        self._r_hist, self._y_hist, self._u_hist = list(r), list(y), list(u)

    def reset(self) -> None:
        self._r_hist = [0.0] * self.HISTORY
        self._y_hist = [0.0] * self.HISTORY
        self._u_hist = [0.0] * self.HISTORY


class ModelReferenceForceController(ForceLawBase):
    """Basic scheme of Rubio 2013 fig. 1: a fixed β, feed command from force samples.

    update(force_reference [N], force_measured [N]) → feed command f_c [mm/s], unclamped
    (the caller clamps and may report the applied value with record_applied()).
    set_depth() gives the known axial depth of cut (the paper assumes it known).
    """

    PARAMS: ClassVar[type[ForceControlParams]] = ForceControlParams

    def __init__(
        self,
        model: ForceProcessModel,
        params: ForceControlParams = ForceControlParams(),
        feed_min: float = -math.inf,
        feed_max: float = math.inf,
    ) -> None:
        del feed_min, feed_max  # one design, no shadow loops to simulate in the feed range
        self.beta = params.beta
        self.designer = ForceControlDesigner(model, params)
        self.model = model
        self._depth = model.depth_at(0.0)
        self._ctrl = RstController(self.designer.design(self.beta), model.process_gain(self._depth))

    @property
    def active_beta(self) -> float:
        return self.beta

    @property
    def design(self) -> RstDesign:
        return self._ctrl.design

    def set_depth(self, depth: float) -> None:
        """Axial depth of cut a_dc [mm] now in force (scales S and T by 1/K_p)."""
        self._ctrl.set_gain(self.model.process_gain(depth))
        self._depth = depth

    def update(self, force_reference: float, force_measured: float) -> float:
        return self._ctrl.update(force_reference, force_measured)

    def record_applied(self, feed: float) -> None:
        self._ctrl.record_applied(feed)

    def reset(self) -> None:
        self._ctrl.reset()
