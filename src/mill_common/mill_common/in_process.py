"""Nodes built in the test's own process, each set of them in a ROS context of its own.

What the in-process node tests of every package share: a private domain on loopback, no
command line of the test runner taken for the node's, one context torn down at the end.
`node_factory` makes nodes of one class to look at; `Graph` joins nodes of any kind on one
executor and spins it until something has happened.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from typing import Any


@contextmanager
def _context(nodes: list[Any]) -> Iterator[Any]:
    """A fresh rclpy context with no command line of the test runner's; on exit every node
    in `nodes` is destroyed and the context shut down."""
    import rclpy

    from mill_common import ros_params

    saved = ros_params.command_line
    ros_params.command_line = []
    context = rclpy.Context()
    rclpy.init(args=[], context=context)
    try:
        yield context
    finally:
        for node in nodes:
            node.destroy_node()
        rclpy.try_shutdown(context=context)
        ros_params.command_line = saved


def _renamed(name: str, *ros_args: str) -> list[str]:
    return ['--ros-args', '-r', f'__node:={name}', *ros_args]


@contextmanager
def node_factory(node_class: Any, name: str) -> Iterator[Callable[..., Any]]:
    """make(*ros_args) -> a `node_class` named `name`; every node made is destroyed and the
    context shut down on exit. Sets ROS_AUTOMATIC_DISCOVERY_RANGE and ROS_DOMAIN_ID only
    where unset, in this process."""
    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    os.environ.setdefault('ROS_DOMAIN_ID', str(150 + os.getpid() % 10))
    nodes: list[Any] = []
    with _context(nodes) as context:

        def make(*ros_args: str) -> Any:
            nodes.append(node_class(context=context, cli_args=_renamed(name, *ros_args)))
            return nodes[-1]

        yield make


@contextmanager
def _environment(**values: str) -> Iterator[None]:
    """os.environ with `values` set, as it was again on exit."""
    before = {key: os.environ.get(key) for key in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for key, value in before.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


class Graph:
    """Real rclpy nodes in this process, on one single-threaded executor, in ROS domain
    `first_domain` + this process's id modulo 25 on loopback (both set for the graph's
    lifetime only). Use as a context manager: on exit the executor is shut down, every node
    it holds destroyed and the context shut down. `period` [s] is the longest one spin
    waits for work."""

    def __init__(self, first_domain: int, period: float = 0.05) -> None:
        self.domain = first_domain + os.getpid() % 25
        self.period = period
        self.nodes: list[Any] = []
        self._stack = ExitStack()
        self.context: Any = None
        self.executor: Any = None

    def __enter__(self) -> Graph:
        from rclpy.executors import SingleThreadedExecutor

        with ExitStack() as stack:
            stack.enter_context(
                _environment(
                    ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST', ROS_DOMAIN_ID=str(self.domain)
                )
            )
            self.context = stack.enter_context(_context(self.nodes))
            self.executor = SingleThreadedExecutor(context=self.context)
            stack.callback(self.executor.shutdown)
            self._stack = stack.pop_all()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stack.close()

    def add(self, node: Any) -> Any:
        """`node` (made in self.context) spun by the executor and destroyed on exit."""
        self.nodes.append(node)
        self.executor.add_node(node)
        return node

    def node(self, name: str) -> Any:
        """A plain rclpy node `name`."""
        from rclpy.node import Node

        return self.add(Node(name, context=self.context))

    def named(self, node_class: Any, name: str, *ros_args: str) -> Any:
        """A `node_class` node renamed `name`, as a launch file would start it."""
        return self.add(node_class(context=self.context, cli_args=_renamed(name, *ros_args)))

    def remove(self, node: Any) -> None:
        """`node` gone from the graph now: no longer spun, and destroyed."""
        self.executor.remove_node(node)
        self.nodes.remove(node)
        node.destroy_node()

    def spin_until(self, done: Callable[[], bool], timeout: float = 10.0) -> bool:
        """Spin until done() (asked before each spin) or `timeout` [s]; done() at the end."""
        end = time.monotonic() + timeout
        while time.monotonic() < end and not done():
            self.executor.spin_once(timeout_sec=self.period)
        return done()

    def spin(self, seconds: float) -> None:
        """Spin for `seconds`, whatever happens."""
        self.spin_until(lambda: False, seconds)


def set_one(node: Any, name: str, value: Any) -> Any:
    """The result of setting one parameter, as `ros2 param set` gets it."""
    from rclpy.parameter import Parameter

    (result,) = node.set_parameters([Parameter(name, value=value)])
    return result
