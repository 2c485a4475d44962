"""Harmonic cutting force of Maharof 2018 §3 and eq. (5) (ROS-free).

    F(t) = w · [F̄ + Σ_i A_i sin(2π m_i f_0 t + θ_i)]   for start_time ≤ t < end_time, else 0,

with w the per-axis weights (x, y, z), F̄ the mean, and one eq. (5) term
d(t) = A' sin(ωt + θ) per harmonic ω_i = 2π m_i f_0. Time t is the absolute simulation time,
so the phases θ_i refer to t = 0 whatever start_time is. Sign as in cutting.py (Beltrán 2013
eq. (1)): a positive F_cx resists motion in +x.

Readings (see also /work/shared/papers/README.md):

- Base frequency: f_0 = spindle_speed/60 · teeth, exactly as the DFO (mill_observers/dfo.py)
  so that the force's harmonics are the observer's resonators. The paper cuts at a stated
  1500 rpm and finds 26/52/78 Hz (once "58 Hz", a misprint); no integer reading of 1500 rpm
  gives 26 Hz, and 1560 rpm × 1 (once per revolution, e.g. run-out of the 10 mm cutter) does.
  Defaults: spindle_speed = 1560 rpm, teeth = 1, harmonics = [1, 2, 3] → 26/52/78 Hz.
- Amplitudes: the measured force (Kistler, fig. 2) is not published. They are synthesised
  backwards from the only numbers the paper gives at those frequencies, Table 2's FFT of the
  tracking error of the plain cascade P/PI: 3.158, 0.4511, 0.3711 µm at 26, 52, 78 Hz, read
  as single-sided peak amplitudes. The closed loop of eq. (1) with the §4.1 gains (k_v = 225,
  k_p = 0.00661, k_i = 0.12075, T_d = 1.2 ms), y/d = G/(1 + G (k_p + k_i/s)(s + k_v)) with d an
  input-equivalent voltage, has |y/d| = 0.592, 0.457, 0.360 mm/V there, so the disturbance
  was 5.34, 0.987, 1.03 mV, an acceleration A·d = 0.417, 0.077, 0.081 m/s² of the paper's
  table. The same acceleration of the suite's x carriage (Beltrán 2013 Table 1,
  m_e = m + J/a² = 94.4 kg) needs 39.3, 7.3, 7.6 N: the defaults (checked in the tests).
- Phases: not published; default 0.
- Mean: not published (an FFT of the error shows no DC). Default 45 N: the smallest multiple
  of 5 N that keeps the default force one-signed (its harmonic part spans ±41.1 N with zero
  phases), i.e. a feed force that always resists +x, as a cutting force does.
- Axes: the paper's cut is a straight line along x and only the x axis is studied: the
  default weights are (1, 0, 0).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

from mill_common.declared import ParamSet, param
from mill_common.parameters import (
    ParameterError,
    non_negative,
    number,
    number_list,
    positive,
    positive_or_inf,
    whole_in,
)
from mill_models.harmonics import harmonic_multiples

from mill_plant.cutting import CuttingForceModel, Force3

MAHAROF_SPINDLE_SPEED = 1560.0  # rpm, 26 Hz once per revolution (module docstring)
MAHAROF_TEETH = 1
MAHAROF_HARMONICS = (1.0, 2.0, 3.0)  # 26/52/78 Hz
SYNTHESISED_AMPLITUDES = (39.3, 7.3, 7.6)  # N, back-computed from Table 2 (module docstring)
SYNTHESISED_MEAN = 45.0  # N


def _finite_list(value: Any) -> str | None:
    return number_list(each=number)(value)


def _amplitudes(value: Any) -> str | None:
    return number_list(each=non_negative)(value)


@dataclass(frozen=True)
class HarmonicParams(ParamSet):
    """Maharof 2018 eq. (5): the harmonics of the spindle frequency, their amplitudes and
    phases (one entry per harmonic), the mean, the axes and the time window."""

    PREFIX: ClassVar[str] = 'harmonic'
    spindle_speed: float = param(
        MAHAROF_SPINDLE_SPEED,
        "spindle speed n; base harmonic f_0 = n/60·teeth (1560 rpm × 1 = the paper's 26 Hz)",
        positive,
        unit='rpm',
    )
    teeth: int = param(
        MAHAROF_TEETH,
        'events per spindle revolution in f_0 = n/60·teeth (1 = once per revolution, '
        'flute count = tooth passing)',
        whole_in(1, 100),
        unit='-',
    )
    harmonics: list[float] = param(
        list(MAHAROF_HARMONICS),
        'multiples m_i of f_0 in the force, Maharof 2018 §3 (26/52/78 Hz)',
        harmonic_multiples,
        unit='-',
    )
    amplitudes: list[float] = param(
        list(SYNTHESISED_AMPLITUDES),
        'amplitude A_i of each harmonic, eq. (5) (synthesised from Table 2)',
        _amplitudes,
        unit='N',
    )
    phases: list[float] = param(
        [0.0] * len(MAHAROF_HARMONICS),
        'phase θ_i of each harmonic at t = 0, eq. (5)',
        _finite_list,
        unit='rad',
    )
    mean: float = param(SYNTHESISED_MEAN, 'mean (DC) force F̄', number, unit='N')
    axis_weights: list[float] = param(
        [1.0, 0.0, 0.0],
        'weight of the force on x, y, z (F_axis = weight · F(t))',
        number_list(3),
        unit='-',
    )
    start_time: float = param(0.0, 'the force acts from this time', non_negative, unit='s')
    end_time: float = param(
        math.inf,
        'the force acts until this time (> start_time; .inf = for ever)',
        positive_or_inf,
        unit='s',
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        n = len(self.harmonics)
        for name in ('amplitudes', 'phases'):
            given = getattr(self, name)
            if len(given) != n:
                raise ParameterError(
                    f'{self.PREFIX}.{name}',
                    given,
                    f'must have one entry per harmonic ({n}), got {len(given)}',
                )
        if not self.end_time > self.start_time:
            raise ParameterError(
                f'{self.PREFIX}.end_time',
                self.end_time,
                f'must be > start_time = {self.start_time}',
            )

    @classmethod
    def from_values(cls, values: Mapping[str, Any], owner: str = '') -> HarmonicParams:
        """As ParamSet.from_values; missing phases: zero phase for every harmonic given."""
        harmonics = values.get('harmonics')
        if 'phases' not in values and isinstance(harmonics, list | tuple):
            values = {**values, 'phases': [0.0] * len(harmonics)}
        return super().from_values(values, owner)


class HarmonicForce(CuttingForceModel):
    """Mean plus harmonics of the spindle frequency on chosen axes."""

    PARAMS: ClassVar[type[HarmonicParams]] = HarmonicParams

    def __init__(self, params: HarmonicParams = HarmonicParams()) -> None:
        self.spindle_speed: float = params.spindle_speed
        self.teeth: int = params.teeth
        self.harmonics: tuple[float, ...] = tuple(params.harmonics)
        self.amplitudes: tuple[float, ...] = tuple(params.amplitudes)
        self.phases: tuple[float, ...] = tuple(params.phases)
        self.mean: float = params.mean
        w = params.axis_weights
        self.axis_weights: tuple[float, float, float] = (w[0], w[1], w[2])
        self.start_time: float = params.start_time
        self.end_time: float = params.end_time
        # f_0 = n/60 · teeth, the same base frequency as the DFO (module docstring)
        self.base_frequency: float = self.spindle_speed / 60.0 * self.teeth
        self._omegas = tuple(2.0 * math.pi * m * self.base_frequency for m in self.harmonics)

    @property
    def frequencies(self) -> tuple[float, ...]:
        """Frequencies m_i f_0 of the harmonics [Hz]."""
        return tuple(m * self.base_frequency for m in self.harmonics)

    def profile(self, t: float) -> float:
        """Unweighted force F(t) [N] (zero outside [start_time, end_time))."""
        if not self.start_time <= t < self.end_time:
            return 0.0
        # Maharof 2018 eq. (5), one term per harmonic: F̄ + Σ A_i sin(ω_i t + θ_i)
        return self.mean + math.fsum(
            a * math.sin(w * t + p)
            for a, w, p in zip(self.amplitudes, self._omegas, self.phases, strict=True)
        )

    def force(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> Force3:
        """(F_cx, F_cy, F_cz) [N] at time t; position and velocity do not matter."""
        f = self.profile(t)
        wx, wy, wz = self.axis_weights
        return (wx * f, wy * f, wz * f)
