"""The simulated three-axis machine as a drive backend (mill_plant.backend). ROS-free.

The plant (mill_plant.axis_plant, built by mill_plant.config.build_plant) with
the encoder model (sensor.quantize). Efforts are held between `advance` calls; a NaN
effort brakes its axis (the plant's safety path), as does an axis that is not under
control. For analysis it also offers what only a simulation knows: the true velocities,
the lumped disturbance ξ of each axis and the cutting force.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, ClassVar

from mill_common.signals import AXES

from mill_plant.backend import DriveBackend, Vector3
from mill_plant.config import build_plant
from mill_plant.sensor import quantize
from mill_plant.spindle import SpindleGate


class SimulatedMachine(DriveBackend):
    SIMULATED: ClassVar[bool] = True

    def __init__(self, values: dict[str, Any]) -> None:
        super().__init__(values['axes'])
        self.plant = build_plant(values)
        self.resolution = values['sensor_resolution']
        self._index = [AXES.index(a) for a in self.axes]
        # Every machine axis: an axis not under control gets NaN, i.e. is braked.
        self._held = [math.nan] * len(AXES)

    def read(self) -> list[float]:
        position = self.plant.position
        return [quantize(position[i], self.resolution) for i in self._index]

    def write(self, efforts: Sequence[float]) -> None:
        for i, u in zip(self._index, efforts, strict=True):
            self._held[i] = float(u)

    @property
    def held(self) -> tuple[float, ...]:
        """The input of every machine axis (x, y, z) held now."""
        return tuple(self._held)

    def advance(self, dt: float) -> None:
        self.last_report = self.plant.step(tuple(self._held), dt)

    def spindle(self, speed: float) -> None:
        """No cutting force while the spindle stands (`spindle: reference`: the plant's
        SpindleGate; with `on` it always runs)."""
        gate = self.plant.cutting
        if isinstance(gate, SpindleGate):
            gate.running = speed != 0.0

    def input_units(self) -> dict[str, str]:
        """The unit of each axis's effort: its model's INPUT_UNIT (N·m, or V)."""
        models = self.plant.models
        return {a: models[i].INPUT_UNIT for a, i in zip(self.axes, self._index, strict=True)}

    # -- what only a simulation knows (analysis topics) ------------------------------------
    def truth(self) -> tuple[Vector3, Vector3, Vector3]:
        """True positions, velocities and lumped disturbances ξ of x, y, z (before a step)."""
        return self.plant.position, self.plant.velocity, self.plant.disturbance(self.held)

    def cutting_force(self) -> Vector3:
        return self.plant.cutting_force()
