"""What the drive front end needs of a machine: read positions, write efforts, faults. ROS-free.

The plant node is a drive front end (mill_plant.drive_node): timing, topics, command
watchdog, ownership checks, diagnostics and lifecycle. Below it sits a backend, the way a
ros2_control hardware interface offers `read()` and `write()` to the controller manager:

- `read()` the measured position of every axis [m], now;
- `write(efforts)` the input every axis holds from now on (zero-order hold), in the axis
  model's unit (N·m, or V for voltage-driven drives); NaN means: brake this axis;
- `spindle(speed)` the spindle speed from now on, with `spindle: reference` (mill_plant.spindle);
- `faults()` what is wrong, per axis (an amplifier fault, a limit switch), for /diagnostics;
- `advance(dt)` moves a simulated machine's time on by dt with the held efforts. A real
  machine moves by itself: its backend does nothing here (`SIMULATED = False`), and it can
  run only on the wall clock (timing `realtime`), never in lockstep.

The simulated machine (mill_plant.simulated_machine) is one backend; a hardware backend
implements the same few methods (docs/hardware-driver.md shows one).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from typing import ClassVar

from mill_plant.axis_plant import StepReport

Vector3 = tuple[float, float, float]


class DriveBackend(ABC):
    """One machine's axes as the drive front end sees them."""

    SIMULATED: ClassVar[bool] = False  # whether advance() integrates (lockstep possible)

    def __init__(self, axes: Sequence[str]) -> None:
        self.axes = tuple(axes)
        # What the last advance() did to the efforts (clipped, braked); simulation only.
        self.last_report: StepReport | None = None

    @abstractmethod
    def read(self) -> list[float]:
        """Measured position of every axis [m], in the order of `axes`."""

    @abstractmethod
    def write(self, efforts: Sequence[float]) -> None:
        """Hold these inputs from now on, in the order of `axes`; NaN brakes that axis."""

    def advance(self, dt: float) -> None:  # noqa: B027 - a real machine moves by itself
        """Simulation: integrate dt seconds with the held efforts. Hardware: nothing."""

    def spindle(self, speed: float) -> None:  # noqa: B027 - a machine without one
        """Run the spindle at this speed [rev/min, signed; 0 stops it] from now on (the
        drive's `spindle: reference`). A hardware backend switches its spindle here."""

    def faults(self) -> dict[str, str]:
        """What is wrong now, per axis ({} when all is well)."""
        return {}

    def input_units(self) -> dict[str, str]:
        """The unit of each axis's effort (default N·m): the one place the rest of the suite
        asks (the simulated machine answers with each axis model's INPUT_UNIT)."""
        return dict.fromkeys(self.axes, 'N·m')

    # What only a simulation knows, published for analysis (None: not available).
    def truth(self) -> tuple[Vector3, Vector3, Vector3] | None:
        """True positions, velocities and lumped disturbances ξ of x, y, z."""
        return None

    def cutting_force(self) -> Vector3 | None:
        """The cutting force on the tool [N]."""
        return None
