"""An observer in a loop with N samples between measurement and actuation. ROS-free.

A digital loop always has delay: a command computed from y(k) acts from the next period on
(real time: the drive applies the newest command at its next tick), or N periods later in
general. Two things then go wrong with an observer written for N = 0:

- it predicts with u(k) while the machine runs on u(k − N): the estimate of the disturbance
  absorbs the difference, and with a fast observer (Beltrán's 700 rad/s) the compensation
  loop oscillates and grows — one sample of delay is enough on the slotting job;
- the controller computes a command for period k + N from the state at k.

`DelayCompensation` fixes both, in the manner of a Smith predictor: the observer's time
update uses the command that really acts over [k, k + 1), u(k − N), and the estimate it
returns is the one for the period the new command will act in, x̂(k + N | k), propagated
through the commands already sent but not yet applied. An observer whose model can be run
ahead (`ModelPredictor`: the GPI observer) propagates its own state; for the others the
position is extrapolated with the estimated velocity. With N = 0 it is the plain observer.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from typing import Protocol, runtime_checkable

from mill_common.signals import Estimate

from mill_observers.base import Observer

# Tick jitter below this fraction of a period is not worth a model step.
LATE_RESOLUTION = 1e-3


@runtime_checkable
class IntervalModel(Protocol):
    def elapse(self, u: float, periods: float) -> None:
        """Run the model on for `periods` (a fraction: a tick early or late) with u held."""
        ...


@runtime_checkable
class ModelPredictor(Protocol):
    def predicted(self, inputs: Sequence[float]) -> Estimate:
        """The estimate after further time updates with these inputs (state unchanged)."""
        ...


class DelayCompensation:
    def __init__(self, observer: Observer, delay: int, sample_period: float) -> None:
        if isinstance(delay, bool) or not isinstance(delay, int) or delay < 0:
            raise ValueError(f'delay must be a whole number of samples >= 0, got {delay!r}')
        self.observer = observer
        self.delay = delay
        self.T = sample_period
        # The commands that act over the next N periods: u(k − N) … u(k − 1). Before the
        # first command the drive holds none: zero input.
        self.pending: deque[float] = deque([0.0] * delay)
        # asked once: a runtime Protocol check costs about 10 µs, a sample's whole work here
        self._predictor = observer if isinstance(observer, ModelPredictor) else None
        self._interval = observer if isinstance(observer, IntervalModel) else None

    def correct(self, y: float) -> Estimate:
        """Measurement update with y(k); the estimate for period k + N."""
        est = self.observer.correct(y)
        if self.delay == 0:
            return est
        self.observer.predict(self.pending[0])  # what acts over [k, k + 1)
        if self._predictor is not None:
            return self._predictor.predicted(list(self.pending)[1:])
        lead = self.delay * self.T
        return Estimate(est.position + lead * est.velocity, est.velocity, est.disturbance)

    def restart(self) -> None:
        """Forget the state and the commands in flight (after a brake: none acted)."""
        self.observer.reset()
        self.pending = deque([0.0] * self.delay)

    def coast(self, u: float) -> None:
        """A period whose measurement never came (a state lost on the way): the model runs
        on over it. `u` is the command the drive held then (real time: the newest sent),
        which is also the one that acts over the lost period: it enters the queue first."""
        u = u if math.isfinite(u) else 0.0
        if self.delay == 0:
            self.observer.predict(u)
            return
        self.pending.popleft()
        self.pending.append(u)
        self.observer.predict(self.pending[0])

    def command(self, u: float, late: float = 0.0) -> None:
        """The command computed at sample k (acts from k + N; a braked axis gets no input).

        late: how much more than a whole number of periods passed since the last state, as
        a fraction of a period (negative: early), from the drive's stamps; the model runs
        on that much longer with the command that acted then (observers that can)."""
        u = u if math.isfinite(u) else 0.0
        interval = self._interval if abs(late) > LATE_RESOLUTION else None
        if self.delay == 0:
            self.observer.predict(u)
            if interval is not None:
                interval.elapse(u, late)
            return
        if interval is not None:
            interval.elapse(self.pending[0], late)
        self.pending.popleft()
        self.pending.append(u)
