"""Entry points that a stop signal ends cleanly from the first moment of the process. ROS-free.

A SIGINT or SIGTERM that arrives while Python still imports rclpy (a few hundred ms, seconds
on a busy machine) would end the process by the signal (exit -2 or -15) or print a
KeyboardInterrupt traceback from the middle of an import. The console scripts hold both
signals blocked from their first line until the process has installed its own handlers
(`release_stop_signals`); a signal that arrived meanwhile is then handled like any later
one. The runner's children inherit the block (mill_bringup.graph), since they start with
`python -m`.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import signal
import sys
from collections.abc import Callable
from typing import NoReturn

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


def hold_stop_signals() -> None:
    """Keep SIGINT and SIGTERM pending (not lost) until release_stop_signals."""
    signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)


def release_stop_signals() -> None:
    """Deliver a stop signal held since the start, and any later one, to the handlers."""
    signal.pthread_sigmask(signal.SIG_UNBLOCK, STOP_SIGNALS)


def _no_op(_signum: int, _frame: object) -> None:
    pass


def ignore_stop_signals() -> None:
    """From now on SIGINT and SIGTERM do nothing (a clean-up under way must not break).

    A Python handler that does nothing, not SIG_IGN: a signal already caught but not yet
    handled when the handler becomes SIG_IGN makes Python print "Signal 15 ignored due to
    race condition" with a traceback.
    """
    for signum in STOP_SIGNALS:
        signal.signal(signum, _no_op)


def interrupt_once(_signum: int, _frame: object) -> None:
    """A handler for code that stops by KeyboardInterrupt: the first stop signal raises it,
    later ones (launch's SIGTERM after a SIGINT) are ignored instead of raising again inside
    the clean-up."""
    ignore_stop_signals()
    raise KeyboardInterrupt


def end_process(code: int) -> NoReturn:
    """End this process at once, once its node, executor and ROS context are closed.

    Python's own finalization runs a full garbage collection over every object of numpy,
    scipy and the node: about a second of CPU per node process. Eight nodes ending
    together on a busy 2-core machine took 4 to 6 s, beyond the 5 s `ros2 launch` waits
    after SIGINT before it escalates to SIGTERM (the observers, which load the most, were
    last). Nothing is left for the finalization to do: streams are flushed here.
    """
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(code)


def entry(module: str) -> Callable[[], NoReturn]:
    """A console script's function: hold the stop signals, import `module`, run its main()
    (which releases them once it can handle them) and end the process with its code.

    Ending at once also keeps a late stop signal from killing the process during Python's
    finalization, which gives the signals their default action back (exit -15).
    """

    def main() -> NoReturn:
        hold_stop_signals()
        end_process(int(importlib.import_module(module).main() or 0))

    return main
