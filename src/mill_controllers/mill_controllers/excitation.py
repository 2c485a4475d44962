"""Excitation for identifying an axis: a soft PD hold plus a random binary torque (ROS-free).

The identify job (config/identify.yaml, docs/bring-up.md) records an axis moving under this
law and fits its model to the record (mill_models.identification). What the fit needs is
what the law gives: an input that is rich (a pseudo-random binary sequence whose bits are
independent of the motion), motion in both directions at many speeds, and an axis that
stays near its reference. The bits are of two lengths: most last one to four `bit_period`
(10 ms), whose power lies below ~90 Hz and moves the axis far and fast enough for its
friction to show; for `short_share` of the time (15 %) they last one to four samples,
which carries the power towards the Nyquist frequency at the job's rate (within 20 dB of
its low-frequency level to 0.78 × Nyquist, 390 Hz at 1 kHz, where 10 ms bits alone end near
97 Hz; the response's fit ends at 0.8 × Nyquist),
so that a resonance the loop can reach is measured (mill_models.frequency_response). A
low-bandwidth PD (eq. (9) of Beltrán 2013 with ξ̂ = 0) keeps it
there; being soft, it lets the binary torque move the axis. Above `max_speed` the binary
torque opposes the motion instead of following its sequence, so the speed stays bounded
whatever the true input gain; the controller's following-error trip bounds the travel.

The torque amplitude is asked for as an acceleration, since the input gain b is what the
job is to find: amplitude = acceleration / b with the nominal b the law is given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from mill_common.declared import param
from mill_common.parameters import ParameterError, in_range, non_negative, positive
from mill_common.signals import ControlInputs

from mill_controllers.base import saturate
from mill_controllers.pd_law import AdrcController, PdGains


@dataclass(frozen=True)
class ExcitationParams(PdGains):
    """The PD hold's gains (softer defaults, no tuning rule) and the binary torque."""

    PREFIX: ClassVar[str] = 'excitation'
    omega_c: float = param(
        30.0,
        'bandwidth of the PD hold [rad/s]: low, so that the binary torque moves the axis',
        positive,
    )
    zeta_c: float = param(1.0, 'damping ratio of the PD hold', positive, unit='-')
    acceleration: float = param(
        1.0,
        'amplitude of the binary torque as the acceleration it gives with the nominal '
        'input gain [m/s²]; choose it well above the friction (torque = acceleration / b)',
        positive,
    )
    bit_period: float = param(
        0.01,
        'shortest time between two changes of the binary torque [s]; each bit lasts one '
        'to four of these, at random',
        positive,
    )
    short_share: float = param(
        0.15,
        'share of the time the binary torque spends in short bits of one to four samples '
        '(the rest in bits of bit_period): they carry its power to 0.8 × the Nyquist frequency, '
        'where a resonance that the loop can reach shows (0: bit_period alone)',
        in_range(0.0, 0.9),
        unit='-',
    )
    max_speed: float = param(
        0.05, 'above this speed the binary torque opposes the motion', positive, unit='m/s'
    )
    seed: int = param(
        1,
        'seed of the random sequence (one per axis gives independent sequences)',
        non_negative,
        unit='-',
    )
    torque_limit: float = param(
        5.0,
        'command saturation ±limit [N·m]; the amplitude and the hold must fit in it',
        positive,
    )


class ExcitationController(AdrcController):
    """PD hold (bandwidth omega_c) + ±amplitude random binary torque: bits of 1-4 bit
    periods, and a share of the time bits of 1-4 samples."""

    PARAMS: ClassVar[type[ExcitationParams]] = ExcitationParams

    def __init__(
        self,
        input_gain: float,
        sample_period: float,
        params: ExcitationParams = ExcitationParams(),
    ) -> None:
        super().__init__(input_gain, sample_period, params)
        self.amplitude = params.acceleration / abs(input_gain)  # [N·m]
        if self.amplitude >= params.torque_limit:
            raise ParameterError(
                'excitation.acceleration',
                params.acceleration,
                f'needs {self.amplitude:.3g} N·m, not below excitation.torque_limit = '
                f'{params.torque_limit:g} N·m',
            )
        self._bit = max(1, round(params.bit_period / sample_period))  # [samples]
        # a new bit is short (1-4 samples) with the chance that gives short bits their share
        # of the time: both kinds last 2.5 of their units on average
        share = params.short_share
        self._short_chance = share * self._bit / (share * self._bit + (1.0 - share))
        self._max_speed = params.max_speed
        self._seed = int(params.seed)
        self.reset()

    def reset(self) -> None:
        self._rng = np.random.default_rng(self._seed)
        # whether a bit is short: a stream of its own, so that the signs and the lengths in
        # units are the sequence the seed gave before there were short bits
        self._kinds = np.random.default_rng([self._seed, 1])
        self._sign = 1.0
        self._left = 0  # samples left in the current bit
        self._excitation = 0.0

    def _next_sign(self) -> float:
        if self._left == 0:
            self._sign = 1.0 if self._rng.random() < 0.5 else -1.0
            length = int(self._rng.integers(1, 5))
            self._left = length * (1 if self._kinds.random() < self._short_chance else self._bit)
        self._left -= 1
        return self._sign

    def compute(self, inputs: ControlInputs) -> float:
        hold = super().compute(inputs)
        sign = self._next_sign()  # the sequence advances every sample, whatever the speed
        v = inputs.estimate.velocity
        if abs(v) > self._max_speed:
            sign = -math.copysign(1.0, v)
        self._excitation = sign * self.amplitude
        limit = self.torque_limit
        return saturate(hold + self._excitation, limit)

    def status(self) -> dict[str, float]:
        return {'excitation': self._excitation}
