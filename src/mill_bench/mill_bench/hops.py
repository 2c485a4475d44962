"""Latency per hop of the realtime loop, as one listener received the messages. ROS-free.

The loop of an axis is drive -> observer -> controller -> drive: the drive publishes the
state stamped k (its acquisition time on the system clock, taken before it integrates and
publishes), the observer answers with the estimate stamped k, the controller with the
command stamped k. A listener (the runner's monitor) notes when each of them arrives, on
the same system clock. Per axis and hop, over the states both messages of the hop answer:

    state       arrival of the state minus its stamp (drive -> listener)
    observer    arrival of the estimate minus arrival of the state
    controller  arrival of the command minus arrival of the estimate
    loop        arrival of the command minus arrival of the state

These are differences of take times at one listener, not publish times: a hop also carries
the difference of the two messages' delivery to the listener, and no time the nodes took
themselves.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Protocol

import numpy as np
from mill_bag.cdr import cdr_stamp_ns

from mill_common import topics

Window = tuple[int, int]  # stamps counted: first, last [ns]
Timed = Mapping[str, Sequence[tuple[int, int]]]  # topic -> (stamp, arrival) [ns]

# hop -> (topic its interval ends with, topic it starts with, or None: the stamp itself)
HOPS: dict[str, tuple[Callable[[str], str], Callable[[str], str] | None]] = {
    'state': (topics.state, None),
    'observer': (topics.estimate, topics.state),
    'controller': (topics.joint_command, topics.estimate),
    'loop': (topics.joint_command, topics.state),
}


class TimedSource(Protocol):
    """What hops read of a listener (the runner's Monitor has it)."""

    def messages(self, topic: str) -> Sequence[bytes]: ...

    def arrival_ns(self, topic: str) -> Sequence[int]: ...


def timed_topics(axes: Iterable[str]) -> set[str]:
    """The topics whose arrivals the hops need."""
    return {
        topic(a) for a in axes for topic in (topics.state, topics.estimate, topics.joint_command)
    }


def timed_messages(source: TimedSource, names: Iterable[str]) -> dict[str, list[tuple[int, int]]]:
    """(stamp, arrival) of every message of these topics the source took with a time."""
    out = {}
    for name in names:
        stamps = (cdr_stamp_ns(data) for data in source.messages(name))
        pairs = zip(stamps, source.arrival_ns(name), strict=False)
        out[name] = [(s, a) for s, a in pairs if s is not None]
    return out


def _first_arrivals(pairs: Sequence[tuple[int, int]], window: Window | None) -> dict[int, int]:
    out: dict[int, int] = {}
    for stamp, arrival in pairs:
        if window is None or window[0] <= stamp <= window[1]:
            out.setdefault(stamp, arrival)
    return out


def quantiles_ms(values_ns: Sequence[int]) -> tuple[float, float]:
    """Median and p99 [ms] (as numpy.percentile); NaN for none."""
    if not values_ns:
        return math.nan, math.nan
    ms = np.asarray(values_ns, dtype=float) * 1e-6
    return float(np.median(ms)), float(np.percentile(ms, 99))


def hop_latencies(
    timed: Timed, axes: Sequence[str], window: Window | None = None
) -> dict[str, dict[str, tuple[float, float]]]:
    """Per axis and hop: median and p99 [ms] over the states stamped within `window` (None:
    all); a hop whose messages never came (the floor has no observer) is left out."""
    out: dict[str, dict[str, tuple[float, float]]] = {}
    for axis in axes:
        per_hop = {}
        for hop, (end, start) in HOPS.items():
            ends = _first_arrivals(timed.get(end(axis), ()), window)
            if start is None:  # from the stamp: the drive's clock is the listener's
                deltas = [arrival - stamp for stamp, arrival in ends.items()]
            else:
                starts = _first_arrivals(timed.get(start(axis), ()), window)
                deltas = [a - starts[s] for s, a in ends.items() if s in starts]
            if deltas:
                per_hop[hop] = quantiles_ms(deltas)
        out[axis] = per_hop
    return out
