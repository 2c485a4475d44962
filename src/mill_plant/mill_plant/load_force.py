"""A machine's process load: a constant force plus a harmonic one, on each axis. ROS-free.

What a real machine puts on its axes besides friction: a cutting or process load with a
constant part and a periodic part (the tooth-passing frequency of a milling cutter), acting
only while the axis moves (`while_moving`) or all the time. It is not a paper's model: it
stands for a machine a driver is commissioned on (test/test_realtime_driver.py,
docs/hardware-driver.md), in the plant's sign convention (mill_plant.cutting: a positive
force resists motion in +axis).

    F_i(t) = s_i · (F0_i + A_i · sin(2π f t)),  s_i = 1, or sign(v_i) while moving (0 at rest)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

from mill_common.declared import ParamSet, param
from mill_common.parameters import boolean, non_negative, number_list

from mill_plant.cutting import CuttingForceModel, Force3


@dataclass(frozen=True)
class LoadParams(ParamSet):
    PREFIX: ClassVar[str] = 'load'
    force: list[float] = param(
        [0.0, 0.0, 0.0], 'constant load F0 on x, y, z', number_list(3), unit='N'
    )
    amplitude: list[float] = param(
        [0.0, 0.0, 0.0], 'amplitude A of the harmonic load on x, y, z', number_list(3), unit='N'
    )
    frequency: float = param(60.0, 'frequency f of the harmonic load', non_negative, unit='Hz')
    while_moving: bool = param(
        True,
        'true: the load acts only on a moving axis, against its motion (a process '
        'load); false: it acts all the time in +axis (a spring, a hanging weight)',
        boolean,
    )


class LoadForce(CuttingForceModel):
    PARAMS: ClassVar[type[LoadParams]] = LoadParams

    def __init__(self, params: LoadParams = LoadParams()) -> None:
        self._f0 = tuple(params.force)
        self._a = tuple(params.amplitude)
        self._omega = 2.0 * math.pi * params.frequency
        self.while_moving = params.while_moving

    def force(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> Force3:
        wave = math.sin(self._omega * t)
        out = []
        for f0, a, v in zip(self._f0, self._a, velocity, strict=True):
            side = 1.0
            if self.while_moving:
                side = 0.0 if v == 0.0 else math.copysign(1.0, v)
            out.append(side * (f0 + a * wave))
        return (out[0], out[1], out[2])
