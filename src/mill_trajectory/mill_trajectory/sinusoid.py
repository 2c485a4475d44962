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
from dataclasses import dataclass
from typing import ClassVar

from mill_common.declared import ParamSet, param
from mill_common.parameters import non_negative, number_list, positive

from mill_trajectory.base import Point, Trajectory, TrajectorySample

MAHAROF_AMPLITUDE = (0.01, 0.0, 0.0)
MAHAROF_FREQUENCY = (0.5, 0.5, 0.5)
DEFAULT_DURATION = 4.0


@dataclass(frozen=True)
class SinusoidParams(ParamSet):
    """Maharof 2018 section 4: x = c + A sin(2π f t + φ) per axis."""

    PREFIX: ClassVar[str] = 'sinusoid'
    center: list[float] = param([0.0, 0.0, 0.0], 'centre c of x, y, z', number_list(3), unit='m')
    amplitude: list[float] = param(
        list(MAHAROF_AMPLITUDE),
        'amplitude A of x, y, z (half the peak-to-peak travel)',
        number_list(3),
        unit='m',
    )
    frequency: list[float] = param(
        list(MAHAROF_FREQUENCY),
        'frequency f of x, y, z',
        number_list(3, non_negative),
        unit='Hz',
    )
    phase: list[float] = param([0.0, 0.0, 0.0], 'phase φ of x, y, z', number_list(3), unit='rad')
    duration: float = param(
        DEFAULT_DURATION, 'length of the sine run; end_time = t0 + it', positive, unit='s'
    )
    start_time: float = param(0.0, 'time t0 the sine starts', non_negative, unit='s')


class Sinusoid(Trajectory):
    PARAMS: ClassVar[type[SinusoidParams]] = SinusoidParams

    def __init__(self, params: SinusoidParams = SinusoidParams()) -> None:
        self.center = tuple(params.center)
        self.amplitude = tuple(params.amplitude)
        self.frequency = tuple(params.frequency)
        self.phase = tuple(params.phase)
        self.omega = tuple(2.0 * math.pi * f for f in self.frequency)
        self.start_time = params.start_time
        self.end_time = self.start_time + params.duration

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
