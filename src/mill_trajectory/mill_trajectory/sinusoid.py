"""Sinusoidal reference per axis, Maharof et al. 2018 section 4 (ROS-free).

    x_ref(t) = c + A sin(2π f (t − t0) + φ)   for t0 ≤ t ≤ t0 + duration,

with velocity and acceleration the exact derivatives A ω cos(·) and −A ω² sin(·),
ω = 2π f. Before t0 and after t0 + duration (= end_time) the reference holds the
position at that end with zero velocity and acceleration.

Reading: Maharof 2018 says "sinusoidal reference signal of amplitude 10mm at frequency of
0.5Hz", so 10 mm is the amplitude A (20 mm peak to peak). The default is that reference on
x (y and z held at 0), with φ = 0: the reference then starts at the centre with velocity
A ω ≈ 31.4 mm/s, a velocity step at t0 as in the paper's plain sine (choose φ and c to
start elsewhere). The paper does not state the run length; the default is 4 s, two periods.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from mill_common.parameters import ParamSpec, non_negative, number_list, positive

from mill_trajectory.base import Point, Trajectory, TrajectorySample

MAHAROF_AMPLITUDE = (0.01, 0.0, 0.0)
MAHAROF_FREQUENCY = (0.5, 0.5, 0.5)
DEFAULT_DURATION = 4.0


class Sinusoid(Trajectory):
    PREFIX = 'sinusoid'
    PARAMETERS = (
        ParamSpec('center', [0.0, 0.0, 0.0], 'centre c of x, y, z [m]', number_list(3)),
        ParamSpec(
            'amplitude',
            list(MAHAROF_AMPLITUDE),
            'amplitude A of x, y, z (half the peak-to-peak travel) [m]',
            number_list(3),
        ),
        ParamSpec(
            'frequency',
            list(MAHAROF_FREQUENCY),
            'frequency f of x, y, z [Hz]',
            number_list(3, non_negative),
        ),
        ParamSpec('phase', [0.0, 0.0, 0.0], 'phase φ of x, y, z [rad]', number_list(3)),
        ParamSpec(
            'duration', DEFAULT_DURATION, 'length of the sine run; end_time = t0 + it [s]', positive
        ),
        ParamSpec('start_time', 0.0, 'time t0 the sine starts [s]', non_negative),
    )

    def __init__(
        self,
        center: Sequence[float] = (0.0, 0.0, 0.0),
        amplitude: Sequence[float] = MAHAROF_AMPLITUDE,
        frequency: Sequence[float] = MAHAROF_FREQUENCY,
        phase: Sequence[float] = (0.0, 0.0, 0.0),
        duration: float = DEFAULT_DURATION,
        start_time: float = 0.0,
    ) -> None:
        lists = [tuple(float(v) for v in seq) for seq in (center, amplitude, frequency, phase)]
        if any(len(seq) != 3 for seq in lists):
            raise ValueError('center, amplitude, frequency and phase need three entries each')
        values = [v for seq in lists for v in seq] + [duration, start_time]
        if not all(math.isfinite(v) for v in values):
            raise ValueError('sinusoid parameters must be finite')
        if not duration > 0.0:
            raise ValueError(f'duration must be > 0, got {duration!r}')
        if any(f < 0.0 for f in lists[2]):
            raise ValueError('frequency must be >= 0')
        self.center, self.amplitude, self.frequency, self.phase = lists
        self.omega = tuple(2.0 * math.pi * f for f in self.frequency)
        self.start_time = float(start_time)
        self.end_time = self.start_time + float(duration)

    @classmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> Sinusoid:
        return cls(
            values['center'],
            values['amplitude'],
            values['frequency'],
            values['phase'],
            values['duration'],
            values['start_time'],
        )

    def sample(self, t: float) -> TrajectorySample:
        moving = self.start_time <= t <= self.end_time
        tau = min(max(t, self.start_time), self.end_time) - self.start_time
        pos, vel, acc = [], [], []
        for c, a, w, phi in zip(self.center, self.amplitude, self.omega, self.phase, strict=True):
            arg = w * tau + phi
            s, co = math.sin(arg), math.cos(arg)
            # Maharof 2018 section 4: x = c + A sin(ωt + φ), ẋ = Aω cos(·), ẍ = −Aω² sin(·)
            pos.append(c + a * s)
            vel.append(a * w * co if moving else 0.0)
            acc.append(-a * w * w * s if moving else 0.0)
        return TrajectorySample(tuple(pos), tuple(vel), tuple(acc))  # type: ignore[arg-type]

    def bounds(self, step: float) -> tuple[Point, Point]:
        # the box of the whole sine (a run shorter than a period may not reach it)
        reach = [
            abs(a) if w > 0.0 else 0.0 for a, w in zip(self.amplitude, self.omega, strict=True)
        ]
        held = self.sample(self.start_time).position  # a sine of frequency 0 holds its phase
        lo = tuple(c - r if r else h for c, r, h in zip(self.center, reach, held, strict=True))
        hi = tuple(c + r if r else h for c, r, h in zip(self.center, reach, held, strict=True))
        return lo, hi  # type: ignore[return-value]
