"""The whole machine's joints in one message, as ROS tools read them (`joint_states`). ROS-free.

RViz, Foxglove and robot_state_publisher read one `sensor_msgs/JointState` with every
joint: the drive publishes its axes' measured positions, their velocities (the difference
of the last two positions over their stamps) and the efforts applied over the period that
ends at the stamp (NaN: braked), every `every` samples, so that the topic stays at or below
`joint_states_rate` whatever the sample rate. A sample is counted once (lockstep offers a
waiting step again under the same stamp; that is no new sample).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass


def decimation(rate: float, period: float) -> int:
    """Samples per message so that the messages come at most `rate` times a second
    (0: none)."""
    if rate <= 0.0:
        return 0
    return max(1, math.ceil(1.0 / (rate * period) - 1e-9))


@dataclass(frozen=True)
class JointSample:
    names: tuple[str, ...]
    position: list[float]  # [m]
    velocity: list[float]  # [m/s], NaN before two samples
    effort: list[float]  # the axis's input over the period that ends now, NaN: braked


class JointStates:
    def __init__(self, axes: Sequence[str], rate: float, period: float) -> None:
        self.names = tuple(axes)
        self.every = decimation(rate, period)
        self.samples = 0  # samples seen
        self._last: tuple[int, list[float]] | None = None  # the previous sample's stamp, x

    def sample(
        self, ns: int, positions: Sequence[float], efforts: Sequence[float]
    ) -> JointSample | None:
        """The message of sample ns, when one is due (None otherwise)."""
        last = self._last
        if last is not None and ns <= last[0]:
            return None  # a sample offered again
        x = list(positions)
        if last is None:
            velocity = [math.nan] * len(x)
        else:
            dt = (ns - last[0]) * 1e-9
            velocity = [(a - b) / dt for a, b in zip(x, last[1], strict=True)]
        self._last = (ns, x)
        due = self.every > 0 and self.samples % self.every == 0
        self.samples += 1
        return JointSample(self.names, x, velocity, list(efforts)) if due else None
