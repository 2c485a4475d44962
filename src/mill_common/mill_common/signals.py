"""Plain data exchanged between algorithm cores. ROS-free: cores import this, never rclpy."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields

AXES: tuple[str, ...] = ('x', 'y', 'z')
# The reference's joint that carries the programmed spindle speed (signed rev/min: M3 > 0,
# M4 < 0, off 0), on paths that program one (G-code).
SPINDLE = 'spindle'


def axis_index(axis: str) -> int:
    """Index of a machine axis name in AXES; ValueError names the bad value."""
    try:
        return AXES.index(axis)
    except ValueError:
        raise ValueError(f'axis must be one of {", ".join(AXES)}, got {axis!r}') from None


@dataclass(frozen=True)
class AxisReference:
    """Desired motion of one axis at one instant [m, m/s, m/s^2]."""

    position: float
    velocity: float
    acceleration: float


@dataclass(frozen=True)
class Estimate:
    """Observer output for one axis at one sample.

    position [m], velocity [m/s], disturbance: the lumped disturbance xi of
    Beltrán 2013 eq. (5)-(8), as an acceleration [m/s^2].
    """

    position: float
    velocity: float
    disturbance: float


@dataclass(frozen=True)
class FopdtEstimate:
    """First-order-plus-dead-time model K e^{−θ_d s}/(τ s + 1) identified online.

    gain K [output per input unit], time_constant τ [s], dead_time θ_d [s] (and in
    samples), updates: how many samples the estimator has used so far.
    """

    gain: float
    time_constant: float
    dead_time: float
    dead_time_samples: float
    updates: int = 0

    def as_status(self) -> dict[str, float]:
        """The fields as a name → value map (how observer_state messages carry them)."""
        return {
            'gain': self.gain,
            'time_constant': self.time_constant,
            'dead_time': self.dead_time,
            'dead_time_samples': self.dead_time_samples,
            'updates': float(self.updates),
        }

    @classmethod
    def from_status(cls, values: Mapping[str, float]) -> FopdtEstimate | None:
        """Read back `as_status()`'s map; None if it lacks a field (another observer's)."""
        try:
            return cls(
                values['gain'],
                values['time_constant'],
                values['dead_time'],
                values['dead_time_samples'],
                int(values['updates']),
            )
        except KeyError:
            return None


@dataclass(frozen=True, slots=True)
class ControlInputs:
    """Everything an axis controller gets at one sample: the inputs joined by stamp.

    t [s] is the sample's time; position is the measured position y [m]; reference and
    estimate are the trajectory's and the observer's values for that time; model is the
    observer's identified plant model (rls observer), None when no law asked for it.
    A new per-step input is a field here (the controller node joins the fields other
    than t by stamp, one topic each) and used by the laws that need it.
    """

    t: float
    position: float
    reference: AxisReference
    estimate: Estimate
    model: FopdtEstimate | None = None


# The fields of ControlInputs the controller node joins by stamp (all but t).
JOINED_INPUTS: tuple[str, ...] = tuple(f.name for f in fields(ControlInputs) if f.name != 't')
