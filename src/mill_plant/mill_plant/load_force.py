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
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

from mill_common.parameters import (
    ParamSpec,
    boolean,
    non_negative,
    number_list,
    validate_all,
)

from mill_plant.cutting import CuttingForceModel, Force3


class LoadForce(CuttingForceModel):
    PREFIX: ClassVar[str] = 'load'
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec('force', [0.0, 0.0, 0.0], 'constant load F0 on x, y, z [N]', number_list(3)),
        ParamSpec(
            'amplitude',
            [0.0, 0.0, 0.0],
            'amplitude A of the harmonic load on x, y, z [N]',
            number_list(3),
        ),
        ParamSpec('frequency', 60.0, 'frequency f of the harmonic load [Hz]', non_negative),
        ParamSpec(
            'while_moving',
            True,
            'true: the load acts only on a moving axis, against its motion (a process '
            'load); false: it acts all the time in +axis (a spring, a hanging weight)',
            boolean,
        ),
    )

    def __init__(
        self,
        force: Sequence[float],
        amplitude: Sequence[float] = (0.0, 0.0, 0.0),
        frequency: float = 60.0,
        while_moving: bool = True,
    ) -> None:
        values = [float(v) for v in (*force, *amplitude, frequency)]
        if len(force) != 3 or len(amplitude) != 3 or not all(map(math.isfinite, values)):
            raise ValueError('force and amplitude need 3 finite entries, frequency a finite one')
        self._f0 = tuple(values[:3])
        self._a = tuple(values[3:6])
        self._omega = 2.0 * math.pi * values[6]
        self.while_moving = bool(while_moving)

    @classmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> LoadForce:
        v = validate_all(cls.PARAMETERS, values, prefix=cls.PREFIX + '.')
        return cls(v['force'], v['amplitude'], v['frequency'], v['while_moving'])

    def force(self, t: float, position: Sequence[float], velocity: Sequence[float]) -> Force3:
        wave = math.sin(self._omega * t)
        out = []
        for f0, a, v in zip(self._f0, self._a, velocity, strict=True):
            side = 1.0
            if self.while_moving:
                side = 0.0 if v == 0.0 else math.copysign(1.0, v)
            out.append(side * (f0 + a * wave))
        return (out[0], out[1], out[2])
