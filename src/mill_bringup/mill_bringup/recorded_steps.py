"""The recorder's side of the lockstep handshake: the newest step a bag holds whole. ROS-free.

A lockstep plant with `recorder_window` W publishes the states of step j only once the
recorder has acknowledged step j − W on mill/recorded (mill_plant.drive_cycle). The runner's
monitor feeds every message it records of the job's stepped topics here and publishes what
`heard` returns. However busy the machine, the plant is then never more than W steps ahead
of the bag: no writer's history (2000 samples deep) can overflow before the recorder takes
its samples, and at the end (`freeze`) the plant stops at a step the bag can wait for.

A topic counts once it has been heard: a topic the job does not publish (no observer on an
axis, no cutting-force listener) must not hold the plant. The first topic (the states of
the first axis) counts from the start.
"""

from __future__ import annotations

from collections.abc import Mapping


class RecordedSteps:
    def __init__(self, lags: Mapping[str, int], dt_ns: int, window: int) -> None:
        """lags: stepped topic -> steps its newest message trails the step's states when
        the step is whole (the ground truth of step k goes out with the states of k + 1);
        the first one is required. window: the plant's `recorder_window` [steps]."""
        if window < 1 or not lags:
            raise ValueError('a handshake needs a window of at least one step and a topic')
        self._lag_ns = {topic: lag * dt_ns for topic, lag in lags.items()}
        self._required = next(iter(lags))
        self._newest: dict[str, int] = {}
        self._dt_ns = dt_ns
        self._window_ns = window * dt_ns
        # Acknowledge every quarter window: the plant never waits for an ack that is due.
        self._stride_ns = max(1, window // 4) * dt_ns
        self.sent = -1  # the newest stamp acknowledged
        self.frozen_at: int | None = None  # where the plant stops, once the job is done

    def stepped(self, topic: str) -> bool:
        return topic in self._lag_ns

    def heard(self, topic: str, ns: int) -> int | None:
        """A message of `topic` stamped ns was recorded: the stamp to acknowledge now, if any."""
        lag = self._lag_ns.get(topic)
        if lag is None:
            return None
        if ns + lag > self._newest.get(topic, -1):
            self._newest[topic] = ns + lag
        return self._due()

    def _due(self) -> int | None:
        through, last = self.through, False
        if self.frozen_at is not None:  # no further than the plant may go
            cap = self.frozen_at - self._window_ns
            through, last = min(through, cap), through >= cap
        if through <= self.sent or (through < self.sent + self._stride_ns and not last):
            return None
        self.sent = through
        return through

    @property
    def through(self) -> int:
        """The newest step whose messages have all been recorded (−1: none yet)."""
        if self._required not in self._newest:
            return -1
        return min(self._newest.values())

    def freeze(self, samples: int) -> int | None:
        """The job's `samples` are done: let the plant step once past them (the ground truth
        of the last sample goes out with that step), or as far as it may go already, and no
        further. The stamp to acknowledge now, if any."""
        if self.frozen_at is None:
            # the plant's rule: step j goes out once j T <= acknowledged + W T
            may = (self.sent + self._window_ns) // self._dt_ns * self._dt_ns
            self.frozen_at = max(may, samples * self._dt_ns)
        return self._due()

    @property
    def drained(self) -> bool:
        """Frozen, and every step up to where the plant stops has been recorded."""
        return self.frozen_at is not None and self.through >= self.frozen_at
