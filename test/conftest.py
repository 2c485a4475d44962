"""Fixtures for system tests: real node processes on loopback in a private ROS domain."""

from __future__ import annotations

import contextlib
import itertools
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from mill_common.env import ros_environment

REPO = Path(__file__).resolve().parents[1]
SCENARIO = REPO / 'config' / 'slotting.yaml'
_domains = itertools.count()


def _next_domain() -> str:
    # Spread over 1..100 from the pid so two test runs on one machine rarely meet.
    return str(1 + (os.getpid() * 13 + next(_domains)) % 100)


@pytest.fixture
def ros_env(monkeypatch: pytest.MonkeyPatch) -> dict[str, str]:
    """Environment of this test's ROS processes: loopback only, a private domain.

    Also applied to the test process itself, for tests that talk to the nodes.
    """
    env = ros_environment(os.environ, domain_id=_next_domain())
    env.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    for key in ('ROS_DOMAIN_ID', 'ROS_AUTOMATIC_DISCOVERY_RANGE', 'RMW_IMPLEMENTATION'):
        monkeypatch.setenv(key, env[key])
    return env


class NodeProcess:
    """One node started as `ros2 run` would; output captured."""

    def __init__(self, module: str, args: list[str], env: dict[str, str]) -> None:
        self.cmd = [sys.executable, '-m', module, *args]
        self.proc = subprocess.Popen(
            self.cmd,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            start_new_session=True,
        )

    def wait(self, timeout: float) -> tuple[int, str, str]:
        out, err = self.proc.communicate(timeout=timeout)
        return self.proc.returncode, out, err

    def alive(self) -> bool:
        return self.proc.poll() is None

    def stop(self) -> tuple[int, str, str]:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
        try:
            out, err = self.proc.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, signal.SIGKILL)
            out, err = self.proc.communicate()
        return self.proc.returncode, out, err


@pytest.fixture
def start_node(ros_env: dict[str, str]) -> Iterator:
    """start_node(module, name, *ros_args, params_file=True) -> NodeProcess."""
    started: list[NodeProcess] = []

    def start(module: str, name: str, *ros_args: str, params_file: bool = True) -> NodeProcess:
        args = ['--ros-args', '-r', f'__node:={name}']
        if params_file:
            args += ['--params-file', str(SCENARIO)]
        node = NodeProcess(module, [*args, *ros_args], ros_env)
        started.append(node)
        return node

    yield start
    for node in started:
        node.stop()


def wait_until(predicate, timeout: float, step: float = 0.05) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(step)
    return predicate()


@contextlib.contextmanager
def ros_node(name: str) -> Iterator:
    """A node of the test process in its own context (environment from ros_env)."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = rclpy.create_node(name, context=context)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        try:
            yield node, executor
        finally:
            executor.shutdown()
            node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
