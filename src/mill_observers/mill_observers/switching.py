"""Bumpless replacement of a running observer (ROS-free).

A new observer starts from the next measurement and knows nothing of the past, so its first
velocity and disturbance estimates would jump (and with them an ADRC torque). The
hand-over therefore adds to the new estimate the difference to the last estimate published
by the old observer, fading with the time constant `blend_time`:

    ê(k) = ê_new(k) + δ·r^(k − k_s),  δ = ê_old(k_s − 1) − ê_new(k_s),  r = e^{−T/blend_time}

for the velocity and the disturbance (the position estimate is the new observer's own): at
the switch sample the estimate holds its last value, then moves over to the new observer's.
"""

from __future__ import annotations

import math

from mill_common.signals import Estimate


class EstimateBlend:
    """Offsets the estimates of a just-started observer so that they continue the old ones."""

    def __init__(self, sample_period: float, blend_time: float) -> None:
        if not blend_time >= 0.0:
            raise ValueError(f'blend_time must be >= 0, got {blend_time!r}')
        self._decay = math.exp(-sample_period / blend_time) if blend_time > 0.0 else 0.0
        self._last: Estimate | None = None
        self._pending = False
        self._dv = 0.0
        self._dxi = 0.0

    def resumed(self, previous: EstimateBlend) -> EstimateBlend:
        """This blend (new blend_time) carrying on from `previous`'s last estimate."""
        self._last = previous._last
        return self

    def switch(self) -> None:
        """The observer has been replaced; its next estimate is the first of the new one."""
        self._pending = self._last is not None

    def __call__(self, est: Estimate) -> Estimate:
        if self._pending and self._last is not None:
            self._pending = False
            self._dv = self._last.velocity - est.velocity
            self._dxi = self._last.disturbance - est.disturbance
        elif self._dv or self._dxi:
            self._dv *= self._decay
            self._dxi *= self._decay
        out = Estimate(est.position, est.velocity + self._dv, est.disturbance + self._dxi)
        self._last = out
        return out
