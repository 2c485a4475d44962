"""Inverse-model-based disturbance observer (IMBDO) of Maharof 2018 §4.2 (ROS-free).

Plant and units (Maharof 2018 eq. (1), nominal model WITHOUT the 1.2 ms dead time):

    Y(s) = G_n(s)·(U(s) + D(s)),   G_n(s) = A/(s² + B s + C),

u the amplifier voltage [V], y the x position [mm inside this module; the suite's
position signals are in m and are converted at the interface], d the input-equivalent
disturbance [V] (a cutting force F acting on the table appears as d = F/k_f with k_f the
drive constant in N/V; the sign of d is that of a voltage that pushes the same way).

Observer (Kempf & Kobayashi 1999, the paper's ref. [14]):

    d̂ = Q(s)·[G_n⁻¹(s)·y − u],   Q(s) = ω_c^n/(s + ω_c)^n,   n ≥ 2.

Q·G_n⁻¹ = ω_c^n (s² + B s + C)/(A (s + ω_c)^n) is proper for n ≥ 2 (eq. (3) with m = 0).
Sign convention: y = G_n·(u + d) and d̂ estimates d, so a controller COMPENSATES BY
SUBTRACTING d̂ from its voltage (u = u_c − d̂); CascadePi does exactly that.

Discretisation at the sample period T:
- y-branch Q·G_n⁻¹ by Tustin (bilinear; biproper, so d̂(k) uses y(k));
- u-branch Q by zero-order hold (exact for the held command; strictly proper, so d̂(k)
  uses u up to k−1, the last command actually applied).
Both keep the DC gains, so a constant disturbance on the nominal plant is recovered
exactly in steady state.

Velocity estimate: the backward difference (y(k) − y(k−1))/T, i.e. the mean velocity over
the last sample (half a sample of lag, as an encoder-derived speed), optionally smoothed by
a first-order low-pass v̂(k) = α v̂(k−1) + (1 − α)·Δy/T, α = e^{−2π f_v T}
(velocity_cutoff f_v; .inf = no smoothing, the default). It is a pure function of the
measured position, returned in Estimate.velocity [m/s]. A smoothing filter adds phase lag
inside the velocity loop: with the 1.2 ms plant dead time, the paper's gains and Q at
90 Hz, f_v = 250 Hz already destabilises the cascade at T = 1 ms (see the tests).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from mill_common.declared import ParamSet, param
from mill_common.parameters import ParameterError, non_negative, positive, positive_or_inf
from mill_common.signals import Estimate

from mill_observers.base import Observer

MM_PER_M = 1000.0

# Maharof 2018 eq. (1), x axis: A [mm/(V·s²)], B [1/s], C [1/s²] (T_d = 1.2 ms not modelled)
MAHAROF_A = 78020.0
MAHAROF_B = 163.0
MAHAROF_C = 193.3
MAHAROF_DEAD_TIME = 0.0012


@dataclass(frozen=True)
class MaharofPlant(ParamSet):
    """The nominal model A/(s² + B s + C) of eq. (1), shared by the Maharof observers."""

    plant_gain: float = param(
        MAHAROF_A,
        'gain A of the nominal model A/(s² + B s + C), eq. (1)',
        positive,
        unit='mm/(V·s²)',
    )
    plant_damping: float = param(
        MAHAROF_B,
        'damping B of the nominal model A/(s² + B s + C), eq. (1)',
        non_negative,
        unit='1/s',
    )
    plant_stiffness: float = param(
        MAHAROF_C,
        'stiffness C of the nominal model A/(s² + B s + C), eq. (1)',
        non_negative,
        unit='1/s²',
    )


def check_period(sample_period: float) -> float:
    reason = positive(sample_period)
    if reason:
        raise ParameterError('sample_period', sample_period, reason)
    return float(sample_period)


def _order(value: Any) -> str | None:
    if not isinstance(value, int) or isinstance(value, bool) or not 2 <= value <= 6:
        return 'must be a whole number in [2, 6] (Q·G_n⁻¹ must be proper)'
    return None


class _DiscreteSs:
    """x(k+1) = Ad x(k) + Bd w(k), out(k) = Cd x(k) + Dd w(k), scalar in and out."""

    def __init__(self, num: np.ndarray, den: np.ndarray, T: float, method: str) -> None:
        from scipy.signal import cont2discrete, tf2ss  # slow to load: only when designed

        a, b, c, d = tf2ss(num, den)
        ad, bd, cd, dd, _ = cont2discrete((a, b, c, d), T, method=method)
        self.ad = np.asarray(ad, dtype=float)
        self.bd = np.asarray(bd, dtype=float)[:, 0]
        self.cd = np.asarray(cd, dtype=float)[0]
        self.dd = float(np.asarray(dd, dtype=float)[0, 0])
        self.x = np.zeros(self.ad.shape[0])

    def dc_gain(self) -> float:
        n = self.ad.shape[0]
        return float(self.cd @ np.linalg.solve(np.eye(n) - self.ad, self.bd) + self.dd)

    def rest_at(self, w: float) -> None:
        """State of the filter at rest under the constant input w."""
        n = self.ad.shape[0]
        self.x = np.linalg.solve(np.eye(n) - self.ad, self.bd * w)

    def output(self, w: float) -> float:
        return float(self.cd @ self.x + self.dd * w)

    def step(self, w: float) -> None:
        self.x = self.ad @ self.x + self.bd * w


@dataclass(frozen=True)
class ImbdoParams(MaharofPlant):
    """The nominal model, the Q filter and the velocity's low-pass."""

    PREFIX: ClassVar[str] = 'imbdo'
    q_cutoff: float = param(
        90.0,
        'cut-off frequency f_c of the Q filter ω_c^n/(s + ω_c)^n, ω_c = 2π f_c, eq. (3) and fig. 5',
        positive,
        unit='Hz',
    )
    q_order: int = param(
        2,
        'order n of the Q filter (≥ 2 so that Q·G_n⁻¹ is proper; not given in the paper)',
        _order,
        unit='-',
    )
    velocity_cutoff: float = param(
        math.inf,
        'cut-off f_v of the first-order low-pass on the backward-difference velocity; '
        '.inf = plain backward difference',
        positive_or_inf,
        unit='Hz',
    )


class Imbdo(Observer):
    """Maharof 2018 IMBDO on the x-axis model; d̂ in volts (subtract it from u).

    correct(y [m]) -> Estimate(position=y [m], velocity=v̂ [m/s], disturbance=d̂ [V]);
    predict(u [V]) with u the voltage actually applied over the next sample.
    input_gain (the suite's torque-model b) is not used: this model's input is a voltage.
    """

    PARAMS: ClassVar[type[ImbdoParams]] = ImbdoParams
    DISTURBANCE_UNIT: ClassVar[str] = 'V'  # input-equivalent voltage

    def __init__(
        self, input_gain: float, sample_period: float, params: ImbdoParams = ImbdoParams()
    ) -> None:
        del input_gain  # voltage-input model: A, B, C are this observer's own parameters
        self._T = check_period(sample_period)
        self._a, self._b, self._c = params.plant_gain, params.plant_damping, params.plant_stiffness
        self._q_cutoff, self._q_order = params.q_cutoff, params.q_order
        wc = 2.0 * math.pi * self._q_cutoff
        n = self._q_order
        q_den = np.poly(np.full(n, -wc))  # (s + ω_c)^n
        q_num = np.array([wc**n])
        # Maharof 2018 eq. (3) with m = 0: Q(s) = ω_c^n/(s + ω_c)^n
        self._q_u = _DiscreteSs(q_num, q_den, self._T, 'zoh')
        # Q(s)·G_n⁻¹(s) = ω_c^n (s² + B s + C)/(A (s + ω_c)^n), proper for n ≥ 2
        qg_num = wc**n / self._a * np.array([1.0, self._b, self._c])
        self._q_y = _DiscreteSs(qg_num, q_den, self._T, 'bilinear')
        # First-order low-pass, exact for a held input: α = e^{−ω_v T} (0 when f_v = inf)
        self._alpha = math.exp(-2.0 * math.pi * params.velocity_cutoff * self._T)
        self._y_prev = 0.0
        self._v_mm = 0.0
        self._d_hat = 0.0
        self._initialised = False

    # --- run time --------------------------------------------------------------------

    def correct(self, y: float) -> Estimate:
        """Measurement update with the position y [m]; returns the estimate at this sample.

        The first call (or the first after reset()) starts the filters at rest at y with
        d̂ = 0 (the u-branch at rest under the voltage C/A·y that holds the model there).
        """
        if not math.isfinite(y):
            raise ValueError(f'Imbdo.correct: measured position is not finite: {y!r}')
        y_mm = float(y) * MM_PER_M
        if not self._initialised:
            self._q_y.rest_at(y_mm)
            self._y_prev = y_mm
            self._v_mm = 0.0
            self._q_u.rest_at(self._c / self._a * y_mm)
            self._initialised = True
        # d̂(k) = [Q G_n⁻¹ y](k) − [Q u](k)   (Maharof 2018 fig. 4 / Kempf 1999)
        self._d_hat = self._q_y.output(y_mm) - self._q_u.output(0.0)
        # v̂(k) = α v̂(k−1) + (1 − α)(y(k) − y(k−1))/T
        diff = (y_mm - self._y_prev) / self._T
        self._v_mm = self._alpha * self._v_mm + (1.0 - self._alpha) * diff
        self._y_prev = y_mm
        self._q_y.step(y_mm)
        return Estimate(float(y), self._v_mm / MM_PER_M, self._d_hat)

    def predict(self, u: float) -> None:
        """Time update with the voltage u [V] applied over the next sample."""
        if not self._initialised:
            raise RuntimeError('Imbdo.predict called before the first correct()')
        if not math.isfinite(u):
            raise ValueError(f'Imbdo.predict: command is not finite: {u!r}')
        self._q_u.step(float(u))

    def reset(self) -> None:
        """Forget the state; the next correct() initialises from its measurement."""
        self._initialised = False
        self._d_hat = 0.0

    # --- read-only views -------------------------------------------------------------

    @property
    def sample_period(self) -> float:
        return self._T

    @property
    def initialised(self) -> bool:
        return self._initialised

    @property
    def disturbance(self) -> float:
        """Last d̂ [V]."""
        return self._d_hat

    def q_filter(self) -> tuple[np.ndarray, np.ndarray]:
        """Continuous Q(s) as (num, den), highest power first."""
        wc = 2.0 * math.pi * self._q_cutoff
        return np.array([wc**self._q_order]), np.poly(np.full(self._q_order, -wc))

    def nominal_model(self) -> tuple[np.ndarray, np.ndarray]:
        """Continuous G_n(s) = A/(s² + B s + C) as (num, den) [mm/V]."""
        return np.array([self._a]), np.array([1.0, self._b, self._c])
