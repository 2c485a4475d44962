"""Entry point shared by all mill nodes: --help, clean start-up errors, spin, clean exit."""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import time
from collections.abc import Callable, Sequence
from typing import NoReturn

from mill_common.env import ros_environment
from mill_common.parameters import ParameterError, ParamSpec


class NodeExit(Exception):
    """Why a node ends by itself: an exit code and a message.

    Callbacks do not raise it (an exception thrown through the C++ events
    executor is not a clean way out); they hand it to `request_exit` and the
    spin loop ends the node.
    """

    def __init__(self, code: int, message: str) -> None:
        super().__init__(message)
        self.code = code


def request_exit(node: object, code: int, message: str) -> None:
    """Ask run_node to end `node` after the current callback."""
    if getattr(node, 'exit_request', None) is None:
        node.exit_request = NodeExit(code, message)


def format_parameter_help(specs: Sequence[tuple[str, ParamSpec]]) -> str:
    lines = []
    width = max((len(name) for name, _ in specs), default=10)
    for name, spec in specs:
        default = spec.default
        ro = ' (read-only)' if spec.read_only else ''
        lines.append(f'  {name:<{width}}  {spec.description}{ro} [default: {default!r}]')
    return '\n'.join(lines)


EXECUTORS = ('single', 'events')


def make_executor():
    """The executor named by MILL_EXECUTOR: 'events' (default) or 'single'.

    'events' is rclpy's C++ EventsExecutor (rclpy.experimental in Jazzy): it halves
    the CPU time per message of the SingleThreadedExecutor, and CPU per message is
    what bounds a 1 kHz lockstep loop across processes (README, Performance).
    Callbacks never raise through it: nodes end via `request_exit`.
    """
    import os

    name = os.environ.get('MILL_EXECUTOR', 'events')
    if name == 'events':
        from rclpy.experimental import EventsExecutor

        return EventsExecutor()
    if name != 'single':
        raise ValueError(f'MILL_EXECUTOR must be one of {EXECUTORS}, got {name!r}')
    from rclpy.executors import SingleThreadedExecutor

    return SingleThreadedExecutor()


def install_stop_handlers() -> list[int]:
    """SIGINT/SIGTERM only append to the returned list; the spin loop polls it.

    rclpy's own handler raises KeyboardInterrupt wherever Python happens to be,
    and inside a callback run by the C++ EventsExecutor that aborts the process
    (std::terminate). A flag checked between spin_once calls is a clean way out.
    """
    stop: list[int] = []
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda number, _frame: stop.append(number))
    return stop


def release_node(executor: object | None, node: object | None) -> None:
    """Destroy a node (and its executor) now, before its context is shut down.

    rclpy's shutdown leaves nodes alive until garbage collection, and their DDS readers
    with them: the monitor of a finished run would still count as a subscriber of the next
    run's plant in the same domain, which would then start before the new monitor had
    matched and lose the first samples for it.
    """
    if executor is not None:
        executor.shutdown()
    if node is not None:
        node.destroy_node()


def deliver_before_exit(node: object, timeout: float = 1.0) -> None:
    """Wait (bounded) until every subscriber acknowledged what the node published.

    Destroying a writer drops the samples still in flight, so a recorder could miss the
    last step of a node stopped right after publishing it (seen once in CI: the state of
    one axis of the final step). Publishers without reliable readers return at once.
    """
    from rclpy.duration import Duration

    deadline = time.monotonic() + timeout
    for pub in list(node.publishers):
        left = deadline - time.monotonic()
        if left <= 0:
            return
        # A publisher whose context is already gone has nothing left to deliver.
        with contextlib.suppress(Exception):
            pub.wait_for_all_acked(Duration(nanoseconds=int(left * 1e9)))


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


def _user_args(argv: Sequence[str]) -> list[str]:
    args = list(argv[1:])
    return args[: args.index('--ros-args')] if '--ros-args' in args else args


def run_node(
    make_node: Callable[[], object],
    executable: str,
    summary: str,
    specs: Sequence[tuple[str, ParamSpec]],
    argv: Sequence[str] | None = None,
) -> int:
    """Run one node until it ends or is interrupted; returns the process exit code.

    Started as a process (argv None), it does not return once ROS was initialised: the
    process ends with the code at once (end_process).
    """
    own_process = argv is None
    argv = list(sys.argv if argv is None else argv)
    user = _user_args(argv)
    if '-h' in user or '--help' in user:
        print(
            f'usage: {executable} [--ros-args -p NAME:=VALUE ... --params-file FILE]\n\n'
            f'{summary}\n\nparameters:\n{format_parameter_help(specs)}'
        )
        return 0
    if user:
        print(f'{executable}: error: unexpected arguments {user}; use --ros-args', file=sys.stderr)
        return 2

    # Keep DDS on loopback unless the user chose otherwise (see README, Network).
    for key in ('ROS_AUTOMATIC_DISCOVERY_RANGE',):
        os.environ.setdefault(key, ros_environment({})[key])

    import rclpy
    from rclpy.executors import ExternalShutdownException
    from rclpy.signals import SignalHandlerOptions

    # Until the node spins, SIGINT and SIGTERM end the start-up at once (KeyboardInterrupt in
    # Python code): building a node can take seconds on a busy machine, longer than launch
    # waits after SIGINT. From then on they only set the flag the spin loop polls.
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, signal.default_int_handler)
    stop: list[int] = []
    node = None
    executor = None
    code = 0
    try:
        rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
        node = make_node()
        executor = make_executor()
        executor.add_node(node)
        stop = install_stop_handlers()
        while rclpy.ok() and not stop and getattr(node, 'exit_request', None) is None:
            executor.spin_once(timeout_sec=0.2)
        if getattr(node, 'exit_request', None) is not None:
            raise node.exit_request
    except (ParameterError, ValueError) as exc:
        print(f'{executable}: error: {exc}', file=sys.stderr)
        code = 2
    except NodeExit as exc:
        print(f'{executable}: {"error: " if exc.code else ""}{exc}', file=sys.stderr)
        code = exc.code
    except (KeyboardInterrupt, ExternalShutdownException):
        code = 0
    finally:
        # A second SIGINT (ros2 launch forwards one after the terminal's) or launch's
        # SIGTERM must not break the teardown.
        for signum in (signal.SIGINT, signal.SIGTERM):
            signal.signal(signum, signal.SIG_IGN)
        if node is not None:
            deliver_before_exit(node)
        if executor is not None:
            executor.shutdown()
        if node is not None:
            node.destroy_node()
        if rclpy.ok():
            rclpy.try_shutdown()
        if own_process:
            # The DDS participant goes now (peers see it leave), not in the finalization.
            rclpy.get_default_context().destroy()
    if own_process:
        end_process(code)
    return code
