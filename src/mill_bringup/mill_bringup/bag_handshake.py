"""The recorder's side of the lockstep handshake: the newest step a bag holds whole. ROS-free.

A lockstep plant with `recorder_window` W publishes the states of step j only once the
recorder has acknowledged step j − W on mill/recorded (mill_plant.drive_cycle). The runner's
monitor feeds every message it records of the job's stepped topics here (`heard`) and, after
each write of its bag, publishes what `written` returns: the newest step the bag holds whole
on disk. However busy the machine, the plant is then never more than W steps ahead of the
bag's file: no writer's history (2000 samples deep) can overflow before the recorder takes
its samples, a SIGKILL of the runner costs at most the last W steps of every stepped topic,
and at the end (`freeze`) the plant stops at a step the bag can wait for.

Every stepped topic counts from the start: a step is whole only once each of them holds it,
so the job lists exactly the topics its graph publishes at every step. (A topic counted
only once heard let the plant run on while a controller, not yet matched with the runner,
sent commands nobody recorded: a loaded run lacked commands 0-648 of two axes. The
controllers now also wait for the runner as a reader, mill_bringup.jobs.axis.)
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from mill_common.timebase import sample_index, sample_stamp_ns


class RecordedSteps:
    def __init__(self, lags: Mapping[str, int], period_s: float, window: int) -> None:
        """lags: stepped topic -> samples its newest message trails the step's states when
        the step is whole (the ground truth of step k goes out with the states of k + 1);
        every one is required. period_s: the job's sample period (stamps are
        sample_stamp_ns of it, whole ns or not). window: the clock node's `recorder_window`
        [samples]."""
        if window < 1 or not lags:
            raise ValueError('a handshake needs a window of at least one step and a topic')
        self._lags = dict(lags)
        self._newest: dict[str, int] = {}  # per topic, the newest whole sample it gives
        self._period_s = period_s
        self._window = window
        self._sent = -1  # the newest sample acknowledged
        self._frozen_at: int | None = None  # where the plant stops, once the job is done

    def only(self, kept: Iterable[str]) -> RecordedSteps:
        """The same handshake over the stepped topics among `kept` (a runner without a bag
        hears only the topics it keeps)."""
        keep = set(kept)
        lags = {t: lag for t, lag in self._lags.items() if t in keep}
        return RecordedSteps(lags, self._period_s, self._window)

    def stepped(self, topic: str) -> bool:
        return topic in self._lags

    def heard(self, topic: str, ns: int) -> None:
        """A message of `topic` stamped ns was recorded (taken into the bag's buffer)."""
        lag = self._lags.get(topic)
        if lag is None:
            return
        k = sample_index(ns, self._period_s) + lag
        if k > self._newest.get(topic, -1):
            self._newest[topic] = k

    def written(self) -> int | None:
        """Everything heard so far is in the bag's file (a write just ended): the stamp to
        acknowledge now, if any."""
        return self._due()

    def _due(self) -> int | None:
        through = self._through
        if self._frozen_at is not None:  # no further than the plant may go
            through = min(through, self._frozen_at - self._window)
        if through <= self._sent:
            return None
        self._sent = through
        return sample_stamp_ns(through, self._period_s)

    @property
    def sent(self) -> int:
        """The stamp of the newest step acknowledged (−1: none yet)."""
        return -1 if self._sent < 0 else sample_stamp_ns(self._sent, self._period_s)

    @property
    def _through(self) -> int:
        return min(self._newest.get(topic, -1) for topic in self._lags)

    def behind(self) -> list[str]:
        """The stepped topics the newest whole step waits for (none recorded further)."""
        through = self._through
        return [t for t in self._lags if self._newest.get(t, -1) == through]

    @property
    def through(self) -> int:
        """The stamp of the newest step whose messages have all been recorded (−1: none)."""
        k = self._through
        return -1 if k < 0 else sample_stamp_ns(k, self._period_s)

    def freeze(self, samples: int) -> int | None:
        """The job's `samples` are done: let the plant step once past them (the ground truth
        of the last sample goes out with that step), or as far as it may go already, and no
        further. The stamp to acknowledge now, if any (everything heard so far written)."""
        if self._frozen_at is None:
            # the plant's rule (mill_common.lockstep.RecorderGate): j <= acknowledged + W
            self._frozen_at = max(self._sent + self._window, samples)
        return self._due()

    @property
    def frozen_at(self) -> int | None:
        """The stamp where the plant stops, once frozen."""
        k = self._frozen_at
        return None if k is None else sample_stamp_ns(k, self._period_s)

    @property
    def drained(self) -> bool:
        """Frozen, and every step up to where the plant stops has been recorded."""
        return self._frozen_at is not None and self._through >= self._frozen_at
