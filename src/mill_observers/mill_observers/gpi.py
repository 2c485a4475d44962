"""GPI extended-state observer of Beltrán 2013, sampled three ways (ROS-free).

The paper's observer eq. (15) is continuous with β0 ≈ 8·10¹⁹; sampling it with the
measured position held over the period is unstable at 1 kHz (papers README, "Numerical
notes"). `discretisation` chooses how the sampled loop runs it:

- `current` (the default): the extended model eq. (14) sampled exactly (zero-order hold on
  τ) with a discrete gain placing the error poles at z_i = exp(s_i·T), s_i the roots of
  eq. (18) (mill_observers.chain_design); the estimate at k uses y(k), x̂(k|k);
- `predictor`: the same recursion, but the estimate at k is the one before y(k) comes in,
  x̄(k|k−1) (the classic predictor estimator: one sample older information);
- `continuous`: eq. (15) itself integrated exactly from sample to sample, driven by the
  command as held (exactly what the plant gets) and the position between y(k−1) and y(k)
  the parabola through y(k−2), y(k−1), y(k) (chain_design.continuous_interval): the
  paper's continuous observer up to that interpolation, O(T³·x⁽³⁾) in position. A parabola
  is exact for a constant disturbance; a straight line between two samples would leave
  the estimate of one biased by about 3 % (the test learns_a_constant_disturbance).

With a command delay N ≥ 1 the estimate returned is the model run ahead from x̂(k|k)
(mill_observers.delay), so `predictor` then gives the same as `current`.
"""

from __future__ import annotations

import cmath
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from mill_common.declared import ParamSet, param
from mill_common.parameters import check_gain_and_period, one_of, positive
from mill_common.signals import Estimate
from numpy.polynomial import polynomial as npoly

from mill_observers.base import Observer
from mill_observers.chain_design import (
    ChainDesign,
    ChainObserver,
    advance,
    continuous_interval,
)

_N_STATES = 7  # [η1, η2, ξ1, ξ2, ξ3, ξ4, ξ5] of Beltrán 2013 eq. (14)
DISCRETISATIONS = ('current', 'predictor', 'continuous')


@dataclass(frozen=True)
class GpiParams(ParamSet):
    """The observer's poles, eq. (18), and how it runs sampled."""

    PREFIX: ClassVar[str] = 'gpi'
    omega_o: float = param(
        700.0,
        'natural frequency ω_o of the three observer pole pairs of eq. (18)',
        positive,
        unit='rad/s',
    )
    zeta_o: float = param(
        0.7071, 'damping ratio ζ_o of the three observer pole pairs of eq. (18)', positive, unit='-'
    )
    pole_o: float = param(
        700.0, 'real observer pole p_o of eq. (18), placed at s = −p_o', positive, unit='rad/s'
    )
    discretisation: str = param(
        'current',
        'how the continuous observer of eq. (15) runs sampled: current (exactly sampled '
        'model, discrete poles exp(s_i T), estimate after y(k)), predictor (the same, '
        'estimate before y(k)) or continuous (eq. (15) integrated exactly over each period '
        'with the held command and the position linear between samples)',
        one_of(*DISCRETISATIONS),
    )


class GpiObserver(ChainObserver, Observer):
    """Beltrán 2013 GPI observer for one axis ẍ = b·τ + ξ, ξ a 4th-degree Taylor polynomial.

    Estimates position [m], velocity [m/s] and the lumped disturbance ξ [m/s²] from the
    measured position. Call correct(y) then predict(u) each sample (see base.Observer).
    """

    PARAMS: ClassVar[type[GpiParams]] = GpiParams

    def __init__(
        self, input_gain: float, sample_period: float, params: GpiParams = GpiParams()
    ) -> None:
        self._b, self._T = check_gain_and_period(input_gain, sample_period)
        self.discretisation = params.discretisation
        self._omega_o = params.omega_o
        self._zeta_o = params.zeta_o
        self._pole_o = params.pole_o

        design = ChainDesign(_N_STATES, self._b, self._T, self.continuous_poles())
        self._scale, self._ad_s, self._bd_s = design.scale, design.ad_s, design.bd_s
        self._l_s, self._m_s, self._w_roots = design.l_s, design.m_s, design.w_roots
        T, n = self._T, _N_STATES

        # Plain floats for the 1 kHz loop: faster than numpy for 7 states.
        self._m = [float(v) for v in self._m_s]
        self._g0 = float(self._bd_s[0])
        self._g1 = float(self._bd_s[1])
        self._inv_T = 1.0 / T
        self._inv_T2 = 1.0 / (T * T)
        self._z: list[float] = [0.0] * n
        self._initialised = False
        self._interval: tuple[np.ndarray, ...] | None = None
        if self.discretisation == 'continuous':
            self._interval = continuous_interval(n, self._b, T, self.continuous_poles())
        # continuous: the state, command and position the next period starts from
        self._anchor: tuple[list[float], float, float, float | None] | None = None
        self._y_last: float | None = None  # measured since the last predict()
        self._y_start: float | None = None  # the position the period before started from

    # --- run time --------------------------------------------------------------------

    def correct(self, y: float) -> Estimate:
        """Measurement update with position y [m]; returns x̂(k|k) (`predictor`: x̄(k|k−1)).

        The first call (or the first after reset()) sets position = y, the rest 0.
        A non-finite y raises ValueError and leaves the state untouched.
        """
        if not math.isfinite(y):
            raise ValueError(f'GpiObserver.correct: measured position is not finite: {y!r}')
        self._y_last = float(y)
        z = self._z
        if not self._initialised:
            z[:] = [float(y), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
            self._initialised = True
        elif self._interval is not None:
            z = self._z = self._integrated(float(y))
        else:
            before = self._estimate(z)
            r = y - z[0]
            m = self._m
            z[0] += m[0] * r
            z[1] += m[1] * r
            z[2] += m[2] * r
            z[3] += m[3] * r
            z[4] += m[4] * r
            z[5] += m[5] * r
            z[6] += m[6] * r
            if self.discretisation == 'predictor':
                return before
        return self._estimate(z)

    def _estimate(self, z: Sequence[float]) -> Estimate:
        return Estimate(z[0], z[1] * self._inv_T, z[2] * self._inv_T2)

    def _integrated(self, y: float) -> list[float]:
        """`continuous`: eq. (15) over the period since the last predict(), to y(k)."""
        assert self._interval is not None
        phi, g_u, g_y, g_d, g_c = self._interval
        # no predict() since the last correct(): a period of zero length, nothing to run
        z0, u, y0, y_before = self._anchor or (self._z, 0.0, y, None)
        self._anchor = None
        # the parabola through y(k−2), y(k−1), y(k) (a line at the first period)
        c = 0.0 if y_before is None else 0.5 * (y - 2.0 * y0 + y_before)
        out = phi @ np.asarray(z0) + g_u * u + g_y * y0 + g_d * (y - y0 - c) + g_c * c
        return [float(v) for v in out]

    def predict(self, u: float) -> None:
        """Time update x̄(k+1) = Ad·x̂(k|k) + Bd·u with u [N·m] held over the period.

        Raises RuntimeError before the first correct(), ValueError for a non-finite u
        (the state is left untouched, so one bad command cannot poison the observer).
        """
        if not self._initialised:
            raise RuntimeError('GpiObserver.predict called before the first correct()')
        if not math.isfinite(u):
            raise ValueError(f'GpiObserver.predict: command is not finite: {u!r}')
        if self._interval is not None:
            # a period without a measurement (coast) starts from the model's position
            y0 = self._y_last if self._y_last is not None else self._z[0]
            self._anchor = (self._z, u, y0, self._y_start)
            self._y_start, self._y_last = y0, None
        self._z = self._step(self._z, u)

    def _step(self, z: list[float], u: float) -> list[float]:
        z0, z1, z2, z3, z4, z5, z6 = z
        # Scaled exact ZOH model: z⁺_i = Σ_{j≥i} z_j/(j−i)! + b·T²·[1/2, 1, 0, …]_i·u
        return [
            z0 + z1 + z2 / 2.0 + z3 / 6.0 + z4 / 24.0 + z5 / 120.0 + z6 / 720.0 + self._g0 * u,
            z1 + z2 + z3 / 2.0 + z4 / 6.0 + z5 / 24.0 + z6 / 120.0 + self._g1 * u,
            z2 + z3 + z4 / 2.0 + z5 / 6.0 + z6 / 24.0,
            z3 + z4 + z5 / 2.0 + z6 / 6.0,
            z4 + z5 + z6 / 2.0,
            z5 + z6,
            z6,
        ]

    def predicted(self, inputs: Sequence[float]) -> Estimate:
        """The estimate after further time updates with these commands; the state is kept.

        After predict() the state is x̄(k+1); this gives x̄(k+1+len(inputs)) with the model of
        eq. (14) — what a loop with that many samples of delay acts on.
        """
        z = self._z
        for u in inputs:
            z = self._step(z, u)
        return self._estimate(z)

    def elapse(self, u: float, periods: float) -> None:
        """The period since the last predict() is `periods` longer (tick jitter)."""
        super().elapse(u, periods)
        if self._anchor is not None and math.isfinite(u):
            # continuous: the model alone over the extra time, then eq. (15) over a period
            z0, held, y0, y_before = self._anchor
            self._anchor = (advance(z0, self._g0, self._g1, held, periods), held, y0, y_before)

    def reset(self) -> None:
        """Forget the state; the next correct() initialises from its measurement."""
        self._z = [0.0] * _N_STATES
        self._initialised = False
        self._anchor, self._y_last, self._y_start = None, None, None

    # --- read-only views -------------------------------------------------------------

    @property
    def input_gain(self) -> float:
        """b of eq. (5) [(m/s²)/(N·m)]."""
        return self._b

    @property
    def sample_period(self) -> float:
        """T [s]."""
        return self._T

    @property
    def initialised(self) -> bool:
        return self._initialised

    @property
    def state(self) -> np.ndarray:
        """Current state in raw units [m, m/s, m/s², m/s³, m/s⁴, m/s⁵, m/s⁶] (a copy).

        After correct() this is x̂(k|k); after predict() it is x̄(k+1).
        """
        return np.asarray(self._z, dtype=float) / self._scale

    def continuous_poles(self) -> np.ndarray:
        """The seven roots s_i of eq. (18) [rad/s] (complex)."""
        w, zeta, p = self._omega_o, self._zeta_o, self._pole_o
        root = w * cmath.sqrt(zeta * zeta - 1.0)
        pair = [-zeta * w + root, -zeta * w - root]
        # Beltrán 2013 eq. (18): (s + p_o)(s² + 2 ζ_o ω_o s + ω_o²)³ (ζ_{o,1} read as ζ_{o,i})
        return np.array([complex(-p, 0.0), *pair * 3])

    def continuous_coefficients(self) -> np.ndarray:
        """[β6, β5, …, β0] of eq. (17) for the poles of eq. (18) (documentation only)."""
        # Beltrán 2013 eq. (17): s⁷ + β6 s⁶ + … + β1 s + β0
        coeffs = npoly.polyfromroots(self.continuous_poles()).real  # β0 … β6, 1
        return coeffs[-2::-1].copy()

    def discrete_poles(self) -> np.ndarray:
        """Designed error poles z_i = exp(s_i·T)."""
        return 1.0 + self._w_roots

    def error_poles(self) -> np.ndarray:
        """Eigenvalues of the discrete error matrix Ad − L·C, computed from the gain.

        The three pole pairs are triple roots, so eig() returns each to only about
        (machine ε)^(1/3); the characteristic polynomial itself is accurate to ~ε.
        """
        n = _N_STATES
        err = np.triu(self._ad_s, k=1) - np.outer(self._l_s, np.eye(n)[0])
        return 1.0 + np.linalg.eigvals(err)

    def discrete_model(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(Ad, Bd, C) of the exactly sampled eq. (14) in raw units."""
        s = self._scale
        ad = self._ad_s * s[None, :] / s[:, None]
        bd = self._bd_s / s
        c = np.zeros(_N_STATES)
        c[0] = 1.0
        return ad, bd, c

    def gains(self) -> tuple[np.ndarray, np.ndarray]:
        """(M, L) in raw units: x̂(k|k) = x̄ + M·(y − C x̄), predictor gain L = Ad·M."""
        return self._m_s / self._scale, self._l_s / self._scale
