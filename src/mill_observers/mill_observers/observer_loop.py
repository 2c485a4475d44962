"""One axis, one sample: what the observer does with a state and the command before it. ROS-free.

The observer node and the offline simulator both call `ObserverLoop.step` once per sample,
so a distributed run equals the offline one by construction. At the sample of y(k):

1. the time update with the command that acted over the period before (the controller's
   answer to y(k − 1); None at the first sample after a start or a switch): in the loop's
   delay (mill_observers.delay) the model is fed u(k − 1 − N), and periods whose state
   never arrived (`missed`, real time) are run through with the command held then;
2. the measurement update with y(k): the estimate for the period the next command acts in;
3. after a run-time switch the estimate continues the old observer's (EstimateBlend).
"""

from __future__ import annotations

from mill_common.signals import Estimate, FopdtEstimate

from mill_observers.base import Observer
from mill_observers.delay import DelayCompensation
from mill_observers.switching import EstimateBlend


class ObserverLoop:
    def __init__(
        self, observer: Observer, command_delay: int, sample_period: float, blend_time: float
    ) -> None:
        self._comp = DelayCompensation(observer, command_delay, sample_period)
        self._blend = EstimateBlend(sample_period, blend_time)
        self.started = False  # a sample has been stepped (the next one has a command before)

    @property
    def observer(self) -> Observer:
        return self._comp.observer

    def replace(self, loop: ObserverLoop) -> ObserverLoop:
        """`loop` (a new observer or new gains) carrying on where this one stopped: it
        starts from the next measurement, its estimate continuing this one's."""
        if self.started:
            loop._blend.resumed(self._blend).switch()
        return loop

    def step(self, y: float, acted: float | None, missed: int = 0) -> Estimate:
        """The estimate at the sample of y; `acted` is the command of the sample before
        (None at the first), `missed` the periods since then whose state was lost."""
        if acted is not None and self.started:
            for _ in range(missed):
                self._comp.coast(acted)
            self._comp.command(acted)
        self.started = True
        return self._blend(self._comp.correct(y))

    def model_estimate(self) -> FopdtEstimate | None:
        return self._comp.observer.model_estimate()

    def status(self) -> dict[str, float]:
        return self._comp.observer.status()
