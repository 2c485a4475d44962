"""One axis, one sample: what the observer does with a state and the command before it. ROS-free.

The observer node and the offline simulator both call `ObserverLoop.step` once per sample,
so a distributed run equals the offline one by construction. At the sample of y(k):

1. the time update with the command that acted over the period before (the controller's
   answer to y(k − 1); None at the first sample after a start or a switch): in the loop's
   delay (mill_observers.delay) the model is fed u(k − 1 − N), and periods whose state
   never arrived (`missed`, real time) are run through with the command held then. A
   brake request (NaN) holds the axis and tells nothing of its dynamics: the observer
   stands still, and when commands return it restarts at rest where the axis is, from
   `hold_torque` as at a start: what it estimated while the axis moved (friction in the
   direction it went, a load that acts while cutting) does not act on an axis at rest, and
   applied on release it would throw the axis (millimetres, in test_link_loss); a vertical
   axis's weight is what `hold_torque` gives (tune writes it for every axis);
2. the measurement update with y(k): the estimate for the period the next command acts in;
   the first one starts from `hold_torque`, the input known to hold the axis (its weight);
3. after a run-time switch the estimate continues the old observer's (EstimateBlend).
"""

from __future__ import annotations

import math

from mill_common.signals import Estimate, FopdtEstimate

from mill_observers.base import Observer
from mill_observers.delay import DelayCompensation
from mill_observers.switching import EstimateBlend


class ObserverLoop:
    def __init__(
        self,
        observer: Observer,
        command_delay: int,
        sample_period: float,
        blend_time: float,
        hold_torque: float = 0.0,
    ) -> None:
        self._comp = DelayCompensation(observer, command_delay, sample_period)
        self._blend = EstimateBlend(sample_period, blend_time)
        self.started = False  # a sample has been stepped (the next one has a command before)
        self._hold_torque = hold_torque
        self._last: Estimate | None = None
        self._braked = False

    @property
    def observer(self) -> Observer:
        return self._comp.observer

    def replace(self, loop: ObserverLoop) -> ObserverLoop:
        """`loop` (a new observer or new gains) carrying on where this one stopped: it
        starts from the next measurement, its estimate continuing this one's."""
        if self.started:
            loop._blend.resumed(self._blend).switch()
        return loop

    def step(self, y: float, acted: float | None, missed: int = 0, late: float = 0.0) -> Estimate:
        """The estimate at the sample of y; `acted` is the command of the sample before
        (None at the first), `missed` the periods since then whose state was lost, `late`
        the time beyond whole periods since then, in periods (real time: tick jitter)."""
        last = self._last
        if acted is not None and not math.isfinite(acted) and last is not None:
            self._braked = True  # held by the brake: at rest, the disturbance as it was
            self._last = Estimate(y, 0.0, last.disturbance)
            return self._last
        hold = self._hold_torque if not self.started else None
        if self._braked and last is not None:  # released: start again at rest, here
            hold = self._hold_torque
            self._comp.restart()
            self._braked, self.started = False, False
        if acted is not None and self.started:
            for _ in range(missed):
                self._comp.coast(acted)
            self._comp.command(acted, late)
        self.started = True
        est = self._comp.correct(y)
        if hold:
            xi = self.observer.preload(hold)
            if xi is not None:
                est = Estimate(est.position, est.velocity, xi)
        self._last = est = self._blend(est)
        return est

    def model_estimate(self) -> FopdtEstimate | None:
        return self._comp.observer.model_estimate()

    def status(self) -> dict[str, float]:
        return self._comp.observer.status()
