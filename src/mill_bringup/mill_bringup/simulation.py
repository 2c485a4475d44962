"""The one offline loop: a job in one process, sample by sample. ROS-free.

Every kind of job (mill_bringup.jobs) offers a `Simulation` that makes, per sample, the
calls its graph makes; `run_samples` steps it through the job. Loops that are not built
from a scenario (the β sweep of mill_bringup.force_loop) use the same loop.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol, TypeVar

R = TypeVar('R')
R_co = TypeVar('R_co', covariant=True)


class Simulation(Protocol[R_co]):
    """A job in one process, one sample at a time (what the graph does per sample)."""

    def step(self, k: int) -> None:
        """Sample k: measure, estimate, control, integrate to k + 1."""
        ...

    def record(self) -> R_co:
        """The record of the samples stepped so far."""
        ...

    def finished(self) -> bool:
        """The job has ended with the last sample stepped (a job whose length the run finds:
        a path slowed or sped up by a feed override)."""
        ...


class CoreTimer(Protocol):
    """Time spent in each role's core (benchmark --cores); no-op by default."""

    def start(self) -> None: ...

    def lap(self, role: str, call: bool = True) -> None: ...


class NoTimer:
    def start(self) -> None:
        pass

    def lap(self, role: str, call: bool = True) -> None:
        pass


def run_samples(
    sim: Simulation[R], samples: int, progress: Callable[[int, int], None] | None = None
) -> R:
    """The one offline loop: samples 0 .. samples − 1 in order, or until the job ends."""
    stride = max(1, samples // 100)
    for k in range(samples):
        sim.step(k)
        if progress is not None and k % stride == 0:
            progress(k, samples)
        if sim.finished():
            break
    return sim.record()
