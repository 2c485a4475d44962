"""Harmonic disturbance-force observer (DFO) of Maharof 2018 §4.3 eq. (5)-(11) (ROS-free).

State [x, v, q1_1, q2_1, …, q1_h, q2_h]: position x [mm], velocity v [mm/s] and one
resonator (q1_i [V], q2_i [V/s]) per harmonic ω_i:

    ẋ = v,
    v̇ = −C x − B v + A·(u + Σ_i q1_i),
    q̇1_i = q2_i,   q̇2_i = −ω_i² q1_i,          y = x.

Readings of eq. (10): the printed "−ω_2" is −ω² (eq. (7): d̈ = −ω² d); eq. (10) has one
resonator, here one per harmonic (the paper's 26/52/78 Hz); the printed matrix omits the
stiffness C of eq. (1) — it is kept here (set plant_stiffness = 0 for the printed form).
The disturbance enters as u does, so d̂ = Σ q1_i is an input-equivalent voltage [V]
with y = G_n·(u + d): a controller compensates by SUBTRACTING d̂ (same convention as
Imbdo).

Harmonic frequencies: ω_i = 2π·m_i·f_0 with f_0 = spindle_speed/60·teeth [Hz] and
multiples m_i (default [1, 2, 3]). The paper measures 26/52/78 Hz at a stated 1500 rpm:
1500 rpm gives 25 Hz per revolution (50 Hz tooth passing with 2 flutes), so 26 Hz matches
no integer reading exactly; 1560 rpm × 1 (once per revolution, e.g. run-out) gives 26 Hz
and is the default. set_spindle_speed() re-tunes the observer at run time.

Gains: the paper does not print l_1..l_4. They are placed here (discrete, on the exactly
sampled model with u held, z = e^{sT}) from two parameters: the (x, v) pair at natural
frequency ω_o with damping ζ_o, and each resonator pair at s = ω_i(−ζ_h ± j√(1−ζ_h²)),
i.e. a disturbance-estimation time constant 1/(ζ_h ω_i).

Velocity estimate (Estimate.velocity, m/s): the backward difference (y(k) − y(k−1))/T,
the same signal Imbdo returns, so the cascade's velocity loop is identical with every
Maharof observer (as in the paper, where the observers only add compensation). The
observer state v̂ is available as state[1]; feeding it to the velocity loop adds the
observer's lag and, with the 1.2 ms plant dead time, destabilises the cascade.

Robustness: the model has no dead time; at 78 Hz the plant's 1.2 ms is 34° of phase the
resonators do not know. With the cascade P/PI at T = 0.1 ms, ζ_h = 0.05 is stable and
ζ_h = 0.2 is not (see the tests), hence the default 0.05.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from mill_common.declared import param
from mill_common.parameters import ParameterError, in_range, positive, whole_in
from mill_common.signals import Estimate
from mill_models.harmonics import harmonic_multiples

from mill_observers.base import Observer
from mill_observers.imbdo import MM_PER_M, MaharofPlant, check_period


@dataclass(frozen=True)
class DfoParams(MaharofPlant):
    """The nominal model, the harmonics and the observer's poles."""

    PREFIX: ClassVar[str] = 'dfo'
    spindle_speed: float = param(
        1560.0,
        "spindle speed n; base harmonic f_0 = n/60·teeth (1560 rpm × 1 = the paper's 26 Hz)",
        positive,
        unit='rpm',
    )
    teeth: int = param(
        1,
        'events per spindle revolution in f_0 = n/60·teeth (1 = once per revolution, '
        'flute count = tooth passing)',
        whole_in(1, 100),
        unit='-',
    )
    harmonics: list[float] = param(
        [1.0, 2.0, 3.0],
        'multiples m_i of f_0 that get a resonator, eq. (5)-(7) (26/52/78 Hz)',
        harmonic_multiples,
        unit='-',
    )
    omega_o: float = param(
        2.0 * math.pi * 100.0,
        'natural frequency ω_o of the (x, v) observer pole pair',
        positive,
        unit='rad/s',
    )
    zeta_o: float = param(
        0.7071,
        'damping ratio ζ_o of the (x, v) observer pole pair',
        in_range(0.05, 0.999),
        unit='-',
    )
    zeta_h: float = param(
        0.05,
        'damping ratio ζ_h of each resonator pole pair; estimation time constant 1/(ζ_h ω_i)',
        in_range(0.001, 0.999),
        unit='-',
    )


class Dfo(Observer):
    """Maharof 2018 DFO; d̂ = Σ q̂1_i in volts (subtract it from u).

    correct(y [m]) -> Estimate(position=y [m], velocity=Δy/T [m/s], disturbance=d̂ [V]);
    predict(u [V]) with u the voltage actually applied over the next sample.
    """

    PARAMS: ClassVar[type[DfoParams]] = DfoParams
    DISTURBANCE_UNIT: ClassVar[str] = 'V'  # input-equivalent voltage

    def __init__(
        self, input_gain: float, sample_period: float, params: DfoParams = DfoParams()
    ) -> None:
        del input_gain  # voltage-input model: A, B, C are this observer's own parameters
        self._T = check_period(sample_period)
        self._a, self._b, self._c = params.plant_gain, params.plant_damping, params.plant_stiffness
        self._teeth = params.teeth
        self._multiples = [float(m) for m in params.harmonics]
        self._omega_o, self._zeta_o, self._zeta_h = params.omega_o, params.zeta_o, params.zeta_h
        self._n = 2 + 2 * len(self._multiples)
        self._x = np.zeros(self._n)
        self._y_prev = 0.0
        self._initialised = False
        self._design(params.spindle_speed)

    # --- design ----------------------------------------------------------------------

    def _design(self, spindle_speed: float) -> None:
        f0 = spindle_speed / 60.0 * self._teeth
        omegas = [2.0 * math.pi * m * f0 for m in self._multiples]
        if max(omegas) * self._T >= math.pi:
            raise ParameterError(
                'spindle_speed',
                spindle_speed,
                f'highest harmonic {max(omegas) / (2 * math.pi):.1f} Hz is at or above the '
                f'Nyquist frequency {0.5 / self._T:.1f} Hz',
            )
        n = self._n
        f = np.zeros((n, n))
        g = np.zeros(n)
        # Maharof 2018 eq. (10): ẋ = v, v̇ = −C x − B v + A(u + Σ q1_i)
        f[0, 1] = 1.0
        f[1, 0] = -self._c
        f[1, 1] = -self._b
        g[1] = self._a
        for i, w in enumerate(omegas):
            j = 2 + 2 * i
            f[1, j] = self._a
            # Maharof 2018 eq. (5)-(7), (10): q̇1 = q2, q̇2 = −ω² q1 ("−ω_2" read as −ω²)
            f[j, j + 1] = 1.0
            f[j + 1, j] = -w * w
        h = np.zeros(n)
        h[0] = 1.0  # Maharof 2018 eq. (11): y = [1 0 0 0]·x̂
        # Exact sampling with the command held (ZOH).
        aug = np.zeros((n + 1, n + 1))
        aug[:n, :n] = f * self._T
        aug[:n, n] = g * self._T
        import scipy.linalg  # here: a process without a DFO need not load it (about 20 MB)

        phi = scipy.linalg.expm(aug)
        ad, bd = phi[:n, :n], phi[:n, n]
        poles = self.continuous_poles(omegas)
        z = np.exp(poles * self._T)
        # Place eig(Ad − L H) = z by duality, on a diagonally scaled state for conditioning.
        scale = np.ones(n)
        scale[1] = self._omega_o
        scale[2:] = self._omega_o**2 / self._a
        for i, w in enumerate(omegas):
            scale[3 + 2 * i] *= w
        ad_s = ad / scale[None, :] * scale[:, None]
        from scipy.signal import place_poles  # imported when designed: it is slow to load

        res = place_poles(ad_s.T, h[:, None], z)
        l_s = np.asarray(res.gain_matrix, dtype=float)[0]
        l_gain = l_s / scale
        self._ad, self._bd, self._h = ad, bd, h
        self._l = l_gain
        self._m = np.linalg.solve(ad, l_gain)  # current-estimator gain M = Ad⁻¹ L
        self._omegas = omegas
        self._spindle_speed = float(spindle_speed)
        self._z = z

    def continuous_poles(self, omegas: Sequence[float] | None = None) -> np.ndarray:
        """Designed continuous error poles [rad/s]: (x, v) pair, then one pair per harmonic."""
        omegas = self._omegas if omegas is None else omegas
        out = []
        for w, zeta in [(self._omega_o, self._zeta_o), *[(w, self._zeta_h) for w in omegas]]:
            im = w * math.sqrt(1.0 - zeta * zeta)
            out += [complex(-zeta * w, im), complex(-zeta * w, -im)]
        return np.array(out)

    def set_spindle_speed(self, spindle_speed: float) -> None:
        """Follow a new spindle speed [rpm]: resonators re-tuned, state kept."""
        reason = positive(spindle_speed)
        if reason:
            raise ParameterError(self.PREFIX + '.spindle_speed', spindle_speed, reason)
        self._design(float(spindle_speed))

    # --- run time --------------------------------------------------------------------

    def correct(self, y: float) -> Estimate:
        """Measurement update with the position y [m]; returns x̂(k|k).

        The first call (or the first after reset()) sets x̂ = y, the rest 0.
        """
        if not math.isfinite(y):
            raise ValueError(f'Dfo.correct: measured position is not finite: {y!r}')
        y_mm = float(y) * MM_PER_M
        if not self._initialised:
            self._x = np.zeros(self._n)
            self._x[0] = y_mm
            self._y_prev = y_mm
            self._initialised = True
        else:
            # Maharof 2018 eq. (8), current form: x̂ = x̄ + M (y − H x̄)
            self._x = self._x + self._m * (y_mm - self._x[0])
        v_mm = (y_mm - self._y_prev) / self._T  # backward difference, see module doc
        self._y_prev = y_mm
        return Estimate(float(y), v_mm / MM_PER_M, float(self._x[2::2].sum()))

    def predict(self, u: float) -> None:
        """Time update x̄(k+1) = Ad x̂(k|k) + Bd u with u [V] held over the period."""
        if not self._initialised:
            raise RuntimeError('Dfo.predict called before the first correct()')
        if not math.isfinite(u):
            raise ValueError(f'Dfo.predict: command is not finite: {u!r}')
        self._x = self._ad @ self._x + self._bd * float(u)

    def reset(self) -> None:
        self._initialised = False
        self._x = np.zeros(self._n)

    # --- read-only views -------------------------------------------------------------

    @property
    def sample_period(self) -> float:
        return self._T

    @property
    def initialised(self) -> bool:
        return self._initialised

    @property
    def spindle_speed(self) -> float:
        """Current spindle speed [rpm]."""
        return self._spindle_speed

    @property
    def frequencies(self) -> np.ndarray:
        """Resonator frequencies [Hz]."""
        return np.array(self._omegas) / (2.0 * math.pi)

    @property
    def state(self) -> np.ndarray:
        """[x mm, v mm/s, q1_1 V, q2_1 V/s, …] (a copy)."""
        return self._x.copy()

    def harmonic_estimates(self) -> np.ndarray:
        """q̂1_i of each harmonic [V]; their sum is d̂."""
        return self._x[2::2].copy()

    def discrete_model(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(Ad, Bd, H) of the exactly sampled eq. (10)-(11)."""
        return self._ad.copy(), self._bd.copy(), self._h.copy()

    def gains(self) -> tuple[np.ndarray, np.ndarray]:
        """(M, L): current-estimator gain and predictor gain L = Ad M."""
        return self._m.copy(), self._l.copy()

    def discrete_poles(self) -> np.ndarray:
        """Designed discrete error poles z = e^{sT}."""
        return self._z.copy()
