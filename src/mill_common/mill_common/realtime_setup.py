"""Real-time scheduling of a process that runs a servo loop (the drive, the axis nodes).

A deployment setting, as ros2_control's controller manager has `thread_priority` and
`cpu_affinity`: the parameters `realtime_priority` (SCHED_FIFO priority 1-98, 0: the normal
scheduler) and `cpu_affinity` (CPUs the process may run on) of the nodes of a process. Once
its nodes are built, every thread of the process (the executor's and the middleware's,
which take the messages) gets the highest priority any of its nodes asks for, the CPUs they
name, its memory locked (mlockall: no page fault in the loop) and Python's garbage
collector frozen (gc.freeze: the objects of the start-up are never scanned again, so a
collection stays short).

Where the operating system refuses (no root, no rtprio limit: /etc/security/limits.conf,
the `realtime` group as ros2_control documents it), `apply` says so in one line each and
the process goes on with normal scheduling.
"""

from __future__ import annotations

import ctypes
import gc
import os
from collections.abc import Iterable, Sequence
from typing import Any

MCL_CURRENT, MCL_FUTURE = 1, 2  # <sys/mman.h>

# The runner's listener runs this far below the graph's priority: above every process on the
# normal scheduler (a busy machine starved it: 272-817 states of a 1 kHz run lost), below the
# servo loops it listens to.
LISTENER_BELOW = 10


def wanted(values: Iterable[dict[str, Any]]) -> tuple[int, list[int]]:
    """The process's setting from its nodes' values: the highest priority, their CPUs."""
    priority, cpus = 0, set()
    for v in values:
        if 'realtime_priority' in v:
            priority = max(priority, v['realtime_priority'])
            cpus.update(v['cpu_affinity'])
    return priority, sorted(cpus)


def _threads() -> list[int]:
    try:
        return [int(t) for t in os.listdir('/proc/self/task')]
    except OSError:
        return [0]


def apply(priority: int, cpus: Sequence[int]) -> tuple[list[str], list[str]]:
    """Set this process up; (what was done, what the system refused), one line each."""
    done: list[str] = []
    refused: list[str] = []
    threads = _threads()
    if cpus:
        try:
            for tid in threads:
                os.sched_setaffinity(tid, cpus)
            done.append(f'CPUs {", ".join(map(str, cpus))}')
        except OSError as exc:
            refused.append(f'cpu_affinity {list(cpus)}: {exc.strerror}')
    if priority <= 0:
        return done, refused
    try:
        for tid in threads:
            os.sched_setscheduler(tid, os.SCHED_FIFO, os.sched_param(priority))
        done.append(f'SCHED_FIFO priority {priority} ({len(threads)} threads)')
    except OSError as exc:
        refused.append(
            f'realtime_priority {priority}: {exc.strerror} (run as root, or give the user an '
            'rtprio limit: the realtime group in /etc/security/limits.conf)'
        )
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.mlockall(MCL_CURRENT | MCL_FUTURE) == 0:
        done.append('memory locked')
    else:
        refused.append(f'mlockall: {os.strerror(ctypes.get_errno())} (memlock limit)')
    gc.collect()
    gc.freeze()
    done.append('garbage collector frozen')
    return done, refused


def listener_priority(graph_priority: int) -> int:
    """The SCHED_FIFO priority of a process that listens to a graph at `graph_priority`."""
    return max(1, graph_priority - LISTENER_BELOW)


def listen_at(priority: int) -> list[str]:
    """Every thread of this process (the executor's and the middleware's, which take the
    messages) at SCHED_FIFO `priority`; what it starts later (node processes, new threads)
    on the normal scheduler (SCHED_RESET_ON_FORK). No memory lock, no frozen collector: a
    listener keeps what it hears. Call again once more threads exist. What the system
    refuses, one line each."""
    try:
        for tid in _threads():
            os.sched_setscheduler(
                tid, os.SCHED_FIFO | os.SCHED_RESET_ON_FORK, os.sched_param(priority)
            )
    except OSError as exc:
        return [
            f'listener priority {priority}: {exc.strerror} (run as root, or give the user an '
            'rtprio limit: the realtime group in /etc/security/limits.conf)'
        ]
    return []
