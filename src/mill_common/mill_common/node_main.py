"""Entry point shared by all mill nodes: --help, clean start-up errors, spin, clean exit."""

from __future__ import annotations

import contextlib
import faulthandler
import os
import signal
import sys
import tempfile
import time
import weakref
from collections.abc import Callable, Iterator, Sequence
from typing import TYPE_CHECKING, Any

from mill_common.env import ros_environment
from mill_common.executable import end_process, ignore_stop_signals, release_stop_signals
from mill_common.param_sources import (
    parameter_rule_problem,
    parameter_rules,
    params_file_problem,
    params_files,
    rcl_error_message,
)
from mill_common.parameters import ParameterError, ParamSpec, value_type

if TYPE_CHECKING:  # rclpy is imported only when a node really starts (not for --help)
    from rclpy.executors import Executor
    from rclpy.node import Node


class NodeExit(Exception):
    """Why a node ends by itself: an exit code and a message.

    Callbacks do not raise it (an exception thrown through the C++ events
    executor is not a clean way out); they hand it to `request_exit` and the
    spin loop ends the node.
    """

    def __init__(self, code: int, message: str) -> None:
        super().__init__(message)
        self.code = code


# The exit requested by each running node (the first one counts), read by run_node.
_exit_requests: weakref.WeakKeyDictionary[Node, NodeExit] = weakref.WeakKeyDictionary()


# Futures the spin loops of run_nodes wait on: a request to end completes them.
_wakers: list[Any] = []


def _wake(future: Any) -> None:
    if not future.done():
        future.set_result(True)


def request_exit(node: Node, code: int, message: str) -> None:
    """Ask run_node to end `node` after the current callback."""
    _exit_requests.setdefault(node, NodeExit(code, message))
    for future in list(_wakers):
        _wake(future)


def exit_request(node: Node) -> NodeExit | None:
    """The exit `node` has asked for, if any."""
    return _exit_requests.get(node)


def format_parameter_help(specs: Sequence[tuple[str, ParamSpec]]) -> str:
    lines = []
    width = max((len(name) for name, _ in specs), default=10)
    for name, spec in specs:
        ro = ' (read-only)' if spec.read_only else ''
        constraint = getattr(spec.check, 'text', '')
        kind = value_type(spec) + (f', {constraint}' if constraint else '')
        lines.append(
            f'  {name:<{width}}  {spec.description}{ro} [{kind}; default: {spec.default!r}]'
        )
    return '\n'.join(lines)


EXECUTORS = ('single', 'events')
# In-process messages delivered between two looks at the executor (mill_common.intra_process):
# enough that the look (tens of µs) costs little, few enough that DDS events wait little.
DRAIN_BUDGET = 200
EVENTS_BETWEEN_CHECKS = 32  # executor events handled between two looks at the loop's end
# A node process whose teardown takes longer than this ends at once: once seen in CI, an
# observer spun for 24 min inside rclpy's Node.destroy_node after SIGTERM, slowing every
# run after it. Teardown (acknowledgements up to 1 s per node, then destroying) takes well
# under a second on a quiet machine.
TEARDOWN_LIMIT = 15.0


def make_executor() -> Executor:
    """The executor named by MILL_EXECUTOR: 'events' (default) or 'single'.

    'events' is rclpy's C++ EventsExecutor (rclpy.experimental in Jazzy): it halves
    the CPU time per message of the SingleThreadedExecutor, and CPU per message is
    what bounds a 1 kHz lockstep loop across processes (README, Performance).
    Callbacks never raise through it: nodes end via `request_exit`.
    """
    name = os.environ.get('MILL_EXECUTOR', 'events')
    if name == 'events':
        from rclpy.experimental import EventsExecutor

        return EventsExecutor()
    if name != 'single':
        raise ValueError(f'MILL_EXECUTOR must be one of {EXECUTORS}, got {name!r}')
    from rclpy.executors import SingleThreadedExecutor

    return SingleThreadedExecutor()


def install_stop_handlers(
    wake: Callable[[], None] | None = None, stop: list[int] | None = None
) -> list[int]:
    """SIGINT/SIGTERM only append to the returned list (`stop`, or a new one) and call
    `wake`; the spin loop polls it.

    rclpy's own handler raises KeyboardInterrupt wherever Python happens to be,
    and inside a callback run by the C++ EventsExecutor that aborts the process
    (std::terminate). A flag checked between spins is a clean way out.
    """
    stop = [] if stop is None else stop

    def handler(number: int, _frame: Any) -> None:
        stop.append(number)
        if wake is not None:
            wake()

    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, handler)
    return stop


def release_node(executor: Executor | None, node: Node | None) -> None:
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


def deliver_before_exit(node: Node, timeout: float = 1.0) -> None:
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


class _Kept:
    text = ''


@contextlib.contextmanager
def stderr_kept_back() -> Iterator[_Kept]:
    """Hold back what is written to file descriptor 2 inside the block (rcl's own C log
    lines); the caller prints it, or not, once it knows whether the block succeeded."""
    kept = _Kept()
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as tmp:
        os.dup2(tmp.fileno(), 2)
        try:
            yield kept
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            kept.text = tmp.read().decode(errors='replace')


def _user_args(argv: Sequence[str]) -> list[str]:
    args = list(argv[1:])
    return args[: args.index('--ros-args')] if '--ros-args' in args else args


def run_node(
    make_node: Callable[[], Node],
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
    return run_nodes([('', make_node)], executable, argv, own_process)


def run_nodes(
    makers: Sequence[tuple[str, Callable[[], Node]]],
    executable: str,
    argv: Sequence[str],
    own_process: bool,
    connect: Callable[[Sequence[Node]], None] | None = None,
) -> int:
    """Run nodes in one process, one ROS context and one executor, until one of them ends or
    the process is interrupted; returns the process exit code.

    makers: (label, factory) of each node, built in this order; the label (the node's name
    in a container, '' for a node alone in its process) prefixes that node's errors. A node
    that asks to end (`request_exit`) ends the process, and with it the other nodes, as a
    crash of one node of a ROS 2 component container does. With own_process, the process
    ends at once once ROS was initialised (end_process).
    """
    argv = list(argv)
    # Keep DDS on loopback and repair lost samples within 100 ms (mill_common.env), unless
    # the user chose otherwise (see README, Network).
    for key in ('ROS_AUTOMATIC_DISCOVERY_RANGE', 'FASTRTPS_DEFAULT_PROFILES_FILE'):
        os.environ.setdefault(key, ros_environment({})[key])

    import rclpy
    from rclpy.exceptions import ParameterException
    from rclpy.executors import ExternalShutdownException
    from rclpy.signals import SignalHandlerOptions
    from rclpy.task import Future

    from mill_common import intra_process, ros_params

    for rule in parameter_rules(argv):
        problem = parameter_rule_problem(rule)
        if problem:
            print(f'{executable}: error: -p {rule}: {problem}', file=sys.stderr)
            return 2
    for path in params_files(argv):
        problem = params_file_problem(path)
        if problem:
            print(f'{executable}: error: --params-file {path}: {problem}', file=sys.stderr)
            return 2
    # From here on SIGINT and SIGTERM only append to `stop`, never raise: a KeyboardInterrupt
    # raised wherever Python happens to be (inside rclpy, a __del__) prints a traceback or
    # "Exception ignored". Start-up looks at `stop` between its steps, each well under 5 s.
    stop = install_stop_handlers()
    release_stop_signals()  # held since the first line (mill_common.executable)
    if stop:
        return 0
    try:
        with stderr_kept_back() as kept:
            rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
    except RuntimeError as exc:  # rcl's RCLError: arguments or a parameter file it refuses
        print(f'{executable}: error: {rcl_error_message(str(exc))}', file=sys.stderr)
        return 2
    sys.stderr.write(kept.text)
    ros_params.command_line = argv
    ros_params.process_nodes = tuple(label for label, _make in makers if label)
    nodes: list[tuple[str, Node]] = []
    executor = None
    code = 0
    label = ''
    ended: Future = Future()  # done when a node asks to end or a stop signal arrives
    try:
        for label, make_node in makers:
            if stop:
                raise KeyboardInterrupt  # a stop during start-up ends it as one later does
            nodes.append((label, make_node()))
        label = ''
        if connect is not None:  # nodes of one process that call each other (a container)
            connect([node for _label, node in nodes])
        _schedule([node for _label, node in nodes])
        executor = make_executor()
        for _label, node in nodes:
            executor.add_node(node)
        _wakers.append(ended)
        install_stop_handlers(wake=lambda: _wake(ended), stop=stop)
        local = intra_process.bus()
        while rclpy.ok() and not stop and _request(nodes) is None:
            if local.enabled:
                # Messages between the nodes of this process are delivered here, between
                # executor events, never inside another callback; what no loop waits for
                # goes to DDS once no data callback is ready (a servo cycle's commands first).
                # The ends of the loop are asked once the process is idle, not per event.
                for _ in range(EVENTS_BETWEEN_CHECKS):
                    local.drain(DRAIN_BUDGET)
                    busy = local.activity
                    wait = 0.0 if local.pending() or local.later else 0.2
                    executor.spin_once(timeout_sec=wait)
                    if local.activity == busy and not local.pending():
                        local.flush_later()
                        if wait:
                            break  # idle: look at the signals and the exit requests
            else:
                # The C++ events executor runs callbacks until `ended` is done; the timeout
                # only bounds how long a signal that arrives while no callback runs waits.
                executor.spin_until_future_complete(ended, timeout_sec=0.2)
        request = _request(nodes)
        if request is not None:
            label, exit_ = request
            raise exit_
    except (ParameterError, ValueError, ParameterException) as exc:
        # ParameterException: what rclpy refuses of a value it declares itself at start-up
        # (`use_sim_time:=maybe`: "Trying to set parameter 'use_sim_time' to 'maybe' ...")
        print(f'{executable}: {_of(label)}error: {" ".join(str(exc).split())}', file=sys.stderr)
        code = 2
    except NodeExit as exc:
        print(f'{executable}: {_of(label)}{"error: " if exc.code else ""}{exc}', file=sys.stderr)
        code = exc.code
    except (KeyboardInterrupt, ExternalShutdownException):
        code = 0
    finally:
        # A second SIGINT (ros2 launch forwards one after the terminal's) or launch's
        # SIGTERM must not break the teardown.
        ignore_stop_signals()
        if own_process:
            _end_if_teardown_hangs()
        if ended in _wakers:
            _wakers.remove(ended)
        with contextlib.suppress(Exception):
            intra_process.bus().flush_later()  # what waited for an idle moment goes now
        for _label, node in nodes:
            deliver_before_exit(node)
        if executor is not None:
            executor.shutdown()
        for label, node in nodes:
            try:
                node.destroy_node()
            except ValueError as exc:  # what the node could not finish, e.g. closing a bag
                print(f'{executable}: {_of(label)}error: {exc}', file=sys.stderr)
                code = code or 1
        if rclpy.ok():
            rclpy.try_shutdown()
        if own_process:
            # The DDS participant goes now (peers see it leave), not in the finalization.
            rclpy.get_default_context().destroy()
    if own_process:
        end_process(code)
    return code


def _end_if_teardown_hangs() -> None:
    """End the process with code 1, the Python stacks printed, if its teardown is not over
    in TEARDOWN_LIMIT. faulthandler's watchdog is a C thread: it fires even while a call
    into rclpy holds the interpreter."""
    faulthandler.dump_traceback_later(TEARDOWN_LIMIT, exit=True, file=sys.stderr)


def _schedule(nodes: Sequence[Node]) -> None:
    """The process's real-time scheduling, as its nodes' parameters ask (realtime_setup)."""
    from mill_common import realtime_setup

    params = [getattr(n, 'params', None) for n in nodes]
    priority, cpus = realtime_setup.wanted(p.values for p in params if p is not None)
    if not priority and not cpus:
        return
    done, refused = realtime_setup.apply(priority, cpus)
    logger = nodes[0].get_logger()
    if done:
        logger.info('real-time scheduling: ' + ', '.join(done))
    for line in refused:
        logger.warning(f'real-time scheduling refused, going on without it: {line}')


def _of(label: str) -> str:
    return f'{label}: ' if label else ''


def _request(nodes: Sequence[tuple[str, Node]]) -> tuple[str, NodeExit] | None:
    """The first exit one of the nodes asked for, with its label."""
    for label, node in nodes:
        request = exit_request(node)
        if request is not None:
            return label, request
    return None
