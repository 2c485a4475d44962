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
from rcl_interfaces.srv import DescribeParameters, GetParameters, SetParameters
from rclpy.parameter import Parameter, parameter_value_to_python

from test.two_hosts import TwoHosts, two_hosts

REPO = Path(__file__).resolve().parents[1]
SCENARIO = REPO / 'config' / 'slotting.yaml'
_domains = itertools.count()
# A further variant of a system test (another layout, signal or paper variant of a claim a
# first variant makes in CI): in the extended suite (`scripts/test.sh --all`), out of CI's
# 15 minutes on a 2-core machine.
EXTENDED = pytest.mark.slow


def _next_domain() -> str:
    # Spread over 1..100 from the pid so two test runs on one machine rarely meet; the
    # workers of one run (pytest-xdist: gw0, gw1, ...) never share a domain: each has its own
    # residue modulo their number.
    worker = os.environ.get('PYTEST_XDIST_WORKER', 'gw0')
    workers = int(os.environ.get('PYTEST_XDIST_WORKER_COUNT', '1'))
    index = int(worker[2:]) if worker[2:].isdigit() else 0
    slot = (os.getpid() * 13 + next(_domains)) % (100 // workers)
    return str(1 + slot * workers + index)


@pytest.fixture
def ros_env(monkeypatch: pytest.MonkeyPatch) -> Iterator[dict[str, str]]:
    """Environment of this test's ROS processes: loopback only, a private domain.

    Also applied to the test process itself, for tests that talk to the nodes. What the
    test started and left running is killed afterwards, so that it cannot slow the tests
    after it (a process found is named on stderr).
    """
    env = ros_environment(os.environ, domain_id=_next_domain())
    env.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    for key in ('ROS_DOMAIN_ID', 'ROS_AUTOMATIC_DISCOVERY_RANGE', 'RMW_IMPLEMENTATION'):
        monkeypatch.setenv(key, env[key])
    yield env
    for pid, cmd in _left_in_domain(env['ROS_DOMAIN_ID']):
        print(f'killed a process the test left running: {pid} {cmd}', file=sys.stderr)
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)


def _left_in_domain(domain: str) -> list[tuple[int, str]]:
    """Processes of this machine, other than this one, with ROS_DOMAIN_ID=domain."""
    found = []
    wanted = f'ROS_DOMAIN_ID={domain}'.encode()
    for entry in Path('/proc').iterdir():
        if not entry.name.isdigit() or int(entry.name) == os.getpid():
            continue
        try:
            if wanted in (entry / 'environ').read_bytes().split(b'\0'):
                cmd = (entry / 'cmdline').read_bytes().replace(b'\0', b' ').decode()
                found.append((int(entry.name), cmd[:200]))
        except OSError:
            continue
    return found


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


def spin_until(executor, predicate, timeout: float = 30.0) -> bool:
    """Spin `executor` 10 ms at a time until `predicate` holds (checked after each spin);
    whether it did within `timeout` s."""

    def step() -> bool:
        executor.spin_once(timeout_sec=0.01)
        return predicate()

    return wait_until(step, timeout, step=0.0)


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


class ParameterClient:
    """set / get / describe_parameters of one remote node, each call bounded in time."""

    def __init__(self, node, executor, target: str) -> None:
        self._executor = executor
        self._set = node.create_client(SetParameters, f'/{target}/set_parameters')
        self._get = node.create_client(GetParameters, f'/{target}/get_parameters')
        self._describe = node.create_client(DescribeParameters, f'/{target}/describe_parameters')
        for client in (self._set, self._get, self._describe):
            assert client.wait_for_service(timeout_sec=60), f'{client.srv_name} never appeared'

    def _call(self, client, request):
        future = client.call_async(request)
        self._executor.spin_until_future_complete(future, timeout_sec=30)
        assert future.done(), f'{client.srv_name} did not answer'
        return future.result()

    def set(self, name: str, value):
        request = SetParameters.Request()
        request.parameters = [Parameter(name, value=value).to_parameter_msg()]
        response = self._call(self._set, request)
        assert len(response.results) == 1
        return response.results[0]

    def get(self, *names: str) -> dict:
        response = self._call(self._get, GetParameters.Request(names=list(names)))
        values = zip(names, response.values, strict=True)
        return {n: parameter_value_to_python(v) for n, v in values}

    def describe(self, *names: str) -> dict:
        """name -> rcl_interfaces/msg/ParameterDescriptor, as `ros2 param describe` gets it."""
        response = self._call(self._describe, DescribeParameters.Request(names=list(names)))
        return dict(zip(names, response.descriptors, strict=True))


@contextlib.contextmanager
def busy_cores(n: int = 2) -> Iterator[None]:
    """n processes that keep a core each busy while the block runs (ended on the way out)."""
    spinners = [subprocess.Popen([sys.executable, '-c', 'while True: pass']) for _ in range(n)]
    try:
        yield
    finally:
        for proc in spinners:
            proc.kill()
            proc.wait()


@pytest.fixture
def hosts(ros_env: dict[str, str]) -> Iterator[TwoHosts]:
    """Two network namespaces joined by a veth pair (test/two_hosts.py), removed afterwards."""
    with two_hosts(ros_env) as two:
        yield two


RUNNER = (sys.executable, '-m', 'mill_bringup.runner')


def run_scenario(
    env: dict[str, str], *args: str, timeout: float = 600
) -> subprocess.CompletedProcess[str]:
    """`run_scenario ARGS` to its end, its output captured."""
    return subprocess.run(
        [*RUNNER, *args], env=env, capture_output=True, text=True, timeout=timeout
    )


def start_scenario(env: dict[str, str], *args: str) -> subprocess.Popen[str]:
    """`run_scenario ARGS` started, its output piped."""
    return subprocess.Popen(
        [*RUNNER, *args], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
