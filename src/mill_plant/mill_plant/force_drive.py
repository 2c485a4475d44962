"""The feed drive in front of the Rubio 2013 force process: its feed range (ROS-free).

The process itself, eq. (1)-(3), and its exact simulation are model knowledge shared with the
force controllers (mill_models.force_process). What is plant-side is the drive's limit: a real
drive never runs outside its feed range, so the command it is given, u0 + slope·τ over one
sample, is clamped piece by piece before it reaches the process. The force-process node
(force_process_node.py) and the offline loop (mill_bringup.force_loop) drive the process
through this class.
"""

from __future__ import annotations

import math

import numpy as np
from mill_models.force_process import ForceProcessPlant
from mill_models.holds import clamped_trace


class DrivenForceProcess:
    """The force process behind a feed drive whose feed is limited to [lo, hi] [mm/s].

    apply(u0, slope, duration) applies u0 + slope·τ, clamped piece by piece (the drive
    never runs outside its range), and returns the force on a grid [(times, forces)]
    per smooth piece (split at clamp corners and depth changes) with spacing <= `spacing`.
    """

    def __init__(
        self,
        plant: ForceProcessPlant,
        lo: float = -math.inf,
        hi: float = math.inf,
        spacing: float | None = None,
    ) -> None:
        if not lo <= hi:
            raise ValueError(f'feed range [{lo}, {hi}] is empty')
        self.plant = plant
        self.lo = float(lo)
        self.hi = float(hi)
        self.spacing = float(spacing) if spacing else plant.model.sample_period / 16.0

    def clamp(self, u: float) -> float:
        return min(self.hi, max(self.lo, float(u)))

    def apply(
        self, u0: float, slope: float, duration: float
    ) -> list[tuple[np.ndarray, np.ndarray]]:
        return clamped_trace(self.plant, u0, slope, duration, self.lo, self.hi, self.spacing)
