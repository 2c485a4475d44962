"""Multi-model β-FROH force control, Rubio 2013 §3.2 schemes 1 and 2 (ROS-free).

Both schemes run, beside the real loop, one *shadow loop* per candidate β_l: the
controller designed for β_l (model_reference.py) closing the loop on a copy of the
force-process model (the paper assumes the plant perfectly known, depth profile included)
driven through the β_l hold, with the same feed clamp as the real loop
(mill_models.holds.HeldPlant). A supervisor
chooses, by the index eq. (13), which design drives the real loop and which hold the
feed reconstruction uses.

Our reading of eq. (13) (the paper leaves it open; papers README):

    J_k^(l) = α·Σ_{j=k−M..k} λ^{k−j}·e_j^(l) + β_w·(F_{p,k}^(c) − F_{p,k}^(l))²
              + γ·(f_{c,k}^(c) − f_{c,k}^(l))² + δ·Σ_{j=k−M..k} λ^{k−j}·(F_{p,j} − F_{p,j}^(l))²

- F_p^(l), f_c^(l): force and feed of shadow loop l at the samples; c = c_{k−1}, the
  active model; F_p: the measured force.
- e_j^(l), "the performance of the closed loop (F_pm^(l) − F_p^(l))": with
  index_signal = 'continuous' (default) the mean over sample interval j of
  (F_p^(l)(t) − F_pm(t))², the shadow's *continuous* force against the reference model's
  continuous response to the (held) reference — the paper says the parallel models give
  "the output of all continuous time models F_p1(t), …". With 'sampled' it is
  (F_pm,j^(l) − F_p,j^(l))² at the sampling instants with F_pm^(l) the discrete
  reference model of design l, eq. (13) read literally. Under perfect knowledge every
  design tracks its discrete model exactly, so the sampled term is (to rounding) zero for
  every candidate and cannot rank them; the continuous one ranks inter-sample behaviour.
- Shadow loops are restarted from the real loop (plant state, controller memory, applied
  feed and the index history) whenever the active model or the candidate set changes, so
  J^(l) compares "keep β_l from here on" for every l from the same, real, state.
- Weights are not forced to sum to 1 (scaling does not change the argmin); ties keep the
  active model.
- Switching is allowed once `residence_samples` (τ_R = N_r·T) have passed since the last
  switch (scheme 1) or decision (scheme 2); after `stop_after` samples the active β is
  frozen (§5.2.1: "stop after thirty period times"); 0 never freezes. The on-line
  adaptation of τ_R (rules with J̄_M, J_M) is not implemented: τ_R is a parameter.
- λ = 0.8: §5 lists "S = 0.8" among the parameters; λ is the only parameter of eq. (13)
  not given elsewhere, so we read it as λ.
- Scheme 2 decides every N_r samples (fig. 9: "the values of β at each residence time
  ... two periods"); the printed condition "(k+1)T − kT ≥ MT" is garbled.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from mill_common.declared import param
from mill_common.parameters import (
    ParameterError,
    in_range,
    non_negative,
    non_negative_int,
    number_list,
    one_of,
    positive,
    positive_int,
    whole_in,
)
from mill_models.force_process import ForceProcessModel, ForceProcessPlant
from mill_models.holds import HeldPlant
from mill_models.reference_model import ContinuousReference

from mill_controllers.model_reference import (
    ForceControlDesigner,
    ForceLawBase,
    RstController,
    RstDesignParams,
)


def lfilter(b: Any, a: Any, x: Any, zi: Any) -> Any:
    """scipy.signal.lfilter, imported on first use (scipy.signal takes a second to load)."""
    from scipy.signal import lfilter as scipy_lfilter

    return scipy_lfilter(b, a, x, zi=zi)


PAPER_BETAS: tuple[float, ...] = tuple(1.0 - (i - 1) / 4.0 for i in range(1, 10))


def _forgetting(value: Any) -> str | None:
    reason = positive(value)
    if reason:
        return reason
    return None if value <= 1.0 else 'must be in (0, 1]'


def _weight(default: float, text: str) -> Any:
    return param(default, text, non_negative, unit='-')


_TRACKING = 'α of eq. (13): closed-loop tracking'
_JUMP = 'β_k of eq. (13): output jump at a switch'
_CONTROL = 'γ of eq. (13): control difference'


@dataclass(frozen=True)
class MultiModelParams(RstDesignParams):
    """What both schemes take: the design of every candidate and the index eq. (13).

    The weights' defaults are scheme 1's; scheme 2 declares its own.
    """

    weight_tracking: float = _weight(0.8, _TRACKING)
    weight_jump: float = _weight(0.2, _JUMP)
    weight_control: float = _weight(0.0, _CONTROL)
    weight_identification: float = _weight(0.0, 'δ of eq. (13): measured force vs model output')
    horizon: int = param(
        4, 'M of eq. (13): samples in the sums, k−M..k', whole_in(1, 1000), unit='-'
    )
    forgetting: float = param(0.8, 'λ of eq. (13) in (0, 1]', _forgetting, unit='-')
    residence_samples: int = param(
        2,
        'minimum residence time τ_R = N_r·T between switches, N_r',
        positive_int,
        unit='samples',
    )
    stop_after: int = param(
        30,
        'freeze the active β after this many samples; 0 = never',
        non_negative_int,
        unit='samples',
    )
    index_signal: str = param(
        'continuous',
        "tracking error in eq. (13): 'continuous' (inter-sample, per interval) or "
        "'sampled' (at the instants, literal)",
        one_of('continuous', 'sampled'),
    )
    intersample_intervals: int = param(
        16, 'grid intervals per sample for the continuous error', whole_in(1, 1000), unit='-'
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if sum(self.weights) <= 0.0:
            raise ParameterError(
                self.full_name('weight_tracking'),
                self.weight_tracking,
                'at least one weight of eq. (13) must be > 0',
            )

    @property
    def weights(self) -> tuple[float, float, float, float]:
        """(α, β_k, γ, δ) of eq. (13)."""
        return (
            self.weight_tracking,
            self.weight_jump,
            self.weight_control,
            self.weight_identification,
        )


@dataclass(frozen=True)
class Scheme1Params(MultiModelParams):
    """Scheme 1: a fixed set of candidate β."""

    PREFIX: ClassVar[str] = 'multi_model_1'
    betas: list[float] = param(
        list(PAPER_BETAS),
        'candidate β values, each in [-1, 1] (paper: β(i) = 1 − (i−1)/4, i = 1..9)',
        number_list(None, in_range(-1.0, 1.0)),
    )
    initial_beta: float = param(
        0.0,
        'active β at start, one of betas (0 = ZOH, the shop-floor choice)',
        in_range(-1.0, 1.0),
        unit='-',
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.betas:
            raise ParameterError(self.full_name('betas'), self.betas, 'must not be empty')
        if float(self.initial_beta) not in [float(b) for b in self.betas]:
            raise ParameterError(
                self.full_name('initial_beta'), float(self.initial_beta), 'must be one of betas'
            )


@dataclass(frozen=True)
class Scheme2Params(MultiModelParams):
    """Scheme 2: β and its neighbours β ± Δβ, Δβ divided by m when β is kept."""

    PREFIX: ClassVar[str] = 'multi_model_2'
    weight_jump: float = _weight(0.0, _JUMP)
    weight_control: float = _weight(0.2, _CONTROL)
    initial_beta: float = param(0.0, 'β at start (paper: "arbitrary")', in_range(-1, 1), unit='-')
    delta_beta: float = param(0.2, 'initial Δβ (paper 0.2)', in_range(1e-9, 2.0), unit='-')
    divisor: float = param(
        2.0,
        'm: Δβ ← Δβ/m when β is kept (paper 2)',
        lambda v: positive(v) or (None if v > 1 else 'must be > 1'),
        unit='-',
    )


class _Shadow:
    """One candidate: design for β_l, controller, plant copy, and its index history."""

    def __init__(
        self,
        beta: float,
        designer: ForceControlDesigner,
        lo: float,
        hi: float,
        spacing: float,
        horizon: int,
        r_history: Sequence[float],
    ) -> None:
        self.beta = float(beta)
        self.designer = designer
        model = designer.model
        self.design = designer.design(self.beta)
        self.ctrl = RstController(self.design, model.process_gain(model.depth_at(0.0)))
        self.held = HeldPlant(ForceProcessPlant(model), lo, hi, spacing)
        self.force = 0.0  # F_p^(l) at the current sample
        self.feed = 0.0  # f_c^(l) at the current sample (clamped, applied in the shadow)
        n = horizon + 1
        self.err: deque[float] = deque(maxlen=n)  # e_j^(l), continuous
        self.forces: deque[float] = deque(maxlen=n)  # F_p,j^(l)
        self.ref_out: deque[float] = deque(maxlen=n)  # F_pm,j^(l), discrete reference model
        ref = self.design.reference
        self._ref_num = ref.num  # same length as den: keeps the one-sample delay
        self._ref_den = ref.den
        self._zi = np.zeros(max(len(self._ref_num), len(self._ref_den)) - 1)
        if len(r_history):
            y, self._zi = lfilter(
                self._ref_num, self._ref_den, np.asarray(r_history, dtype=float), zi=self._zi
            )
            self.ref_out.extend(float(v) for v in y[-n:])

    def _filter_reference(self, r: float) -> None:
        y, self._zi = lfilter(self._ref_num, self._ref_den, [r], zi=self._zi)
        self.ref_out.append(float(y[0]))

    def advance(self, reference: ContinuousReference) -> None:
        force, cost, _ = self.held.advance(self.feed, self.beta, reference)
        self.force = force
        self.err.append(cost / self.held.T)

    def observe(self, r: float) -> None:
        """Sample k: record F_p^(l),k and the discrete reference model's F_pm,k^(l)."""
        self._filter_reference(r)
        self.forces.append(self.force)

    def command(self, r: float) -> None:
        """Sample k: this design's feed from r_k and the shadow force, clamped and applied."""
        plant = self.held.plant
        self.ctrl.set_gain(plant.model.gain_at(plant.time))
        u = self.ctrl.update(r, self.force)
        self.feed = self.held.clamp(u)
        self.ctrl.record_applied(self.feed)

    def sync(self, real: _RealLoop, r: float) -> None:
        """Restart from the real loop at sample k (after observe(), replacing command())."""
        self.held.plant.set_state(real.held.plant.state, real.held.plant.time)
        self.held.u_prev = real.held.u_prev
        self.ctrl.load_history(real.ctrl.history())
        self.force = real.held.plant.force
        self.err = deque(real.err, maxlen=self.err.maxlen)
        self.forces = deque(real.forces, maxlen=self.forces.maxlen)
        self.command(r)


class _RealLoop:
    """The supervisor's model of the real loop: the plant copy driven by the applied feed."""

    def __init__(
        self,
        designer: ForceControlDesigner,
        beta: float,
        lo: float,
        hi: float,
        spacing: float,
        horizon: int,
    ) -> None:
        model = designer.model
        self.ctrl = RstController(designer.design(beta), model.process_gain(model.depth_at(0.0)))
        self.held = HeldPlant(ForceProcessPlant(model), lo, hi, spacing)
        self.applied = 0.0
        self.err: deque[float] = deque(maxlen=horizon + 1)
        self.forces: deque[float] = deque(maxlen=horizon + 1)  # measured F_p,j
        self.beta = float(beta)  # hold used over the current interval


class _MultiModelBase(ForceLawBase):
    """Common machinery; subclasses implement _decide(k, r)."""

    PARAMS: ClassVar[type[MultiModelParams]]

    def __init__(
        self,
        model: ForceProcessModel,
        params: MultiModelParams,
        feed_min: float = -math.inf,
        feed_max: float = math.inf,
    ) -> None:
        if not feed_min <= feed_max:
            raise ValueError(f'feed range [{feed_min}, {feed_max}] is empty')
        v = self.params = params
        self.model = model
        self.designer = ForceControlDesigner(model, params)
        self.T = model.sample_period
        self.lo = float(feed_min)
        self.hi = float(feed_max)
        self.horizon = v.horizon
        self.forgetting = v.forgetting
        self.residence = v.residence_samples
        self.stop_after = v.stop_after
        self.continuous_index = v.index_signal == 'continuous'
        self.spacing = self.T / v.intersample_intervals
        self.weights = v.weights
        self._reference = ContinuousReference(self.designer.damping, self.designer.omega_n)
        self._r_full: list[float] = []
        self._k = 0
        self._last_switch = 0
        self._depth = model.depth_at(0.0)
        self._active_beta = self._initial_beta()
        self._real = _RealLoop(
            self.designer, self._active_beta, self.lo, self.hi, self.spacing, self.horizon
        )
        self.shadows: list[_Shadow] = [self._new_shadow(b) for b in self._candidate_betas()]
        self.switch_count = 0

    # --- subclass hooks ----------------------------------------------------------------

    def _initial_beta(self) -> float:
        raise NotImplementedError

    def _candidate_betas(self) -> list[float]:
        raise NotImplementedError

    def _decide(self, k: int, r: float) -> None:
        raise NotImplementedError

    # --- public ------------------------------------------------------------------------

    @property
    def active_beta(self) -> float:
        """β of the hold and design in use now (published by the node)."""
        return self._active_beta

    @property
    def candidate_betas(self) -> list[float]:
        return [s.beta for s in self.shadows]

    @property
    def frozen(self) -> bool:
        return self.stop_after > 0 and self._k >= self.stop_after

    def set_depth(self, depth: float) -> None:
        """Known axial depth of cut a_dc [mm] for the real controller."""
        self._real.ctrl.set_gain(self.model.process_gain(depth))
        self._depth = depth

    def update(self, force_reference: float, force_measured: float) -> float:
        """Feed command f_c,k [mm/s] (unclamped) from F_r,k and F_p,k [N]."""
        if not (math.isfinite(force_reference) and math.isfinite(force_measured)):
            raise ValueError(
                f'{type(self).__name__}.update: non-finite input '
                f'r={force_reference!r}, y={force_measured!r}'
            )
        k = self._k
        if k > 0:
            self._advance_interval()
        r = float(force_reference)
        self._reference.begin(r)
        self._real.forces.append(float(force_measured))
        for sh in self.shadows:
            sh.observe(r)
            sh.command(r)
        self._r_full.append(r)
        if not self.frozen and k - self._last_switch >= self.residence:
            self._decide(k, r)
        real = self._real
        real.beta = self._active_beta
        real.ctrl.set_design(self.designer.design(self._active_beta))
        u = real.ctrl.update(r, float(force_measured))
        real.applied = u
        self._k += 1
        return u

    def record_applied(self, feed: float) -> None:
        """The feed actually applied at this sample (after the clamp) [mm/s]."""
        self._real.ctrl.record_applied(feed)
        self._real.applied = float(feed)

    # --- internals ---------------------------------------------------------------------

    def _new_shadow(self, beta: float) -> _Shadow:
        return _Shadow(
            beta,
            self.designer,
            self.lo,
            self.hi,
            self.spacing,
            self.horizon,
            self._r_full,
        )

    def _advance_interval(self) -> None:
        real = self._real
        _, cost, _ = real.held.advance(real.applied, real.beta, self._reference)
        real.err.append(cost / self.T)
        for sh in self.shadows:
            sh.advance(self._reference)
        self._reference.advance(self.T)

    def _index(self, sh: _Shadow, active: _Shadow | None) -> float:
        a, b, g, d = self.weights
        lam = self.forgetting
        j_val = 0.0
        if a:
            if self.continuous_index:
                terms = list(sh.err)
            else:
                terms = [(m - f) ** 2 for m, f in zip(sh.ref_out, sh.forces, strict=False)]
            j_val += a * sum(lam**i * e for i, e in enumerate(reversed(terms)))
        if active is not None:
            j_val += b * (active.force - sh.force) ** 2 + g * (active.feed - sh.feed) ** 2
        if d:
            meas = list(self._real.forces)[-len(sh.forces) :] if sh.forces else []
            diffs = [(y - f) ** 2 for y, f in zip(meas, sh.forces, strict=False)]
            j_val += d * sum(lam**i * e for i, e in enumerate(reversed(diffs)))
        return j_val

    def indices(self) -> list[float]:
        """J_k^(l) of the candidates at the last sample (for monitoring and tests)."""
        active = self._active_shadow()
        return [self._index(s, active) for s in self.shadows]

    def _active_shadow(self) -> _Shadow | None:
        for s in self.shadows:
            if s.beta == self._active_beta:
                return s
        return None

    def _best(self) -> float:
        active = self._active_shadow()
        scores = [self._index(s, active) for s in self.shadows]
        best = min(scores)
        tol = 1e-12 * max(1.0, abs(best))
        if active is not None:
            cur = scores[self.shadows.index(active)]
            if cur <= best + tol:
                return self._active_beta
        return self.shadows[int(np.argmin(scores))].beta

    def _resync(self, r: float) -> None:
        for sh in self.shadows:
            sh.sync(self._real, r)


class MultiModelScheme1(_MultiModelBase):
    """Scheme 1 (§3.2.1): a fixed set of β; switch to the lowest J_k^(l) after τ_R."""

    PARAMS: ClassVar[type[Scheme1Params]] = Scheme1Params

    def __init__(
        self,
        model: ForceProcessModel,
        params: Scheme1Params = Scheme1Params(),
        feed_min: float = -math.inf,
        feed_max: float = math.inf,
    ) -> None:
        self._betas = [float(b) for b in dict.fromkeys(params.betas)]
        self._init = float(params.initial_beta)
        super().__init__(model, params, feed_min, feed_max)

    def _initial_beta(self) -> float:
        return self._init

    def _candidate_betas(self) -> list[float]:
        return list(self._betas)

    def _decide(self, k: int, r: float) -> None:
        best = self._best()
        if best != self._active_beta:
            self._active_beta = best
            self._last_switch = k
            self.switch_count += 1
            self._resync(r)


class MultiModelScheme2(_MultiModelBase):
    """Scheme 2 (§3.2.3): compare β, β ± Δβ; move by Δβ or divide Δβ by m when staying."""

    PARAMS: ClassVar[type[Scheme2Params]] = Scheme2Params

    def __init__(
        self,
        model: ForceProcessModel,
        params: Scheme2Params = Scheme2Params(),
        feed_min: float = -math.inf,
        feed_max: float = math.inf,
    ) -> None:
        self._delta = params.delta_beta
        self._divisor = params.divisor
        self._init = float(params.initial_beta)
        super().__init__(model, params, feed_min, feed_max)

    @property
    def delta_beta(self) -> float:
        return self._delta

    def _initial_beta(self) -> float:
        return self._init

    def _candidate_betas(self) -> list[float]:
        b = self._active_beta
        lo = max(-1.0, b - self._delta)
        hi = min(1.0, b + self._delta)
        return list(dict.fromkeys([lo, b, hi]))

    def _decide(self, k: int, r: float) -> None:
        best = self._best()
        if best == self._active_beta:
            # Rubio 2013 §3.2.3 step 3: β kept, Δβ ← Δβ/m
            self._delta /= self._divisor
        else:
            # step 4: β moved to β ± Δβ, Δβ kept; the new neighbours are β_new ± Δβ
            self._active_beta = best
            self.switch_count += 1
        self._last_switch = k
        # new shadows: their reference filters have run over r_0..r_k; sync does the rest
        self.shadows = [self._new_shadow(b) for b in self._candidate_betas()]
        self._resync(r)
