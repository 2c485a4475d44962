"""Two hosts on one machine: network namespaces `drive` and `control` joined by a veth pair.

Used by the tests that put the drive on one "host" and the rest of the graph on the other
(test_multi_host, test_link_loss); the `hosts` fixture (test/conftest.py) makes a pair and
removes it afterwards, also when the test fails, or skips the test where namespaces cannot be
created (not root).
"""

from __future__ import annotations

import contextlib
import itertools
import os
import re
import signal
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import IO

import pytest

_count = itertools.count()


def ip(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(['ip', *args], capture_output=True, text=True, timeout=30)


def _must(result: subprocess.CompletedProcess[str]) -> None:
    assert result.returncode == 0, f'{" ".join(result.args)}: {result.stderr.strip()}'


class NamespacesUnavailable(Exception):
    """Network namespaces cannot be created here; str() says why."""


class TwoHosts:
    """Namespace `drive` (the plant) and `control` (the rest), joined by a veth pair.

    A context manager: on the way out, also by an exception, every process in the two
    namespaces is stopped (only this test's can be there) and the namespaces are deleted.
    """

    def __init__(self, env: dict[str, str]) -> None:
        tag = f'{os.getpid()}x{next(_count)}'
        self.drive, self.control = f'mill-drive-{tag}', f'mill-control-{tag}'
        self.drive_dev, self.control_dev = f'md{tag}', f'mc{tag}'  # < 16 characters
        self.env = dict(env, ROS_AUTOMATIC_DISCOVERY_RANGE='SUBNET')
        self.procs: list[subprocess.Popen[str]] = []
        self.created: list[str] = []

    def __enter__(self) -> TwoHosts:
        try:
            first = ip('netns', 'add', self.drive)
        except FileNotFoundError:
            raise NamespacesUnavailable('the ip command (iproute2) is missing') from None
        if first.returncode != 0:
            raise NamespacesUnavailable(f'ip netns add: {first.stderr.strip()}')
        self.created.append(self.drive)
        try:
            self._join()
        except BaseException:
            self.remove()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        self.remove()

    def _join(self) -> None:
        _must(ip('netns', 'add', self.control))
        self.created.append(self.control)
        # Made inside the namespaces: the pair never appears among the host's interfaces.
        _must(
            ip(
                *('link', 'add', self.drive_dev, 'netns', self.drive, 'type', 'veth'),
                *('peer', 'name', self.control_dev, 'netns', self.control),
            )
        )
        for ns, dev, address in (
            (self.drive, self.drive_dev, '10.231.0.1/24'),
            (self.control, self.control_dev, '10.231.0.2/24'),
        ):
            _must(ip('-n', ns, 'addr', 'add', address, 'dev', dev))
            _must(ip('-n', ns, 'link', 'set', 'lo', 'up'))
            _must(ip('-n', ns, 'link', 'set', dev, 'up'))
            # DDS discovery is multicast (239.255.0.1): a host on a LAN sends it by its
            # default route; a new namespace has none, and without this route the
            # participants found each other only now and then.
            _must(ip('-n', ns, 'route', 'add', '224.0.0.0/4', 'dev', dev))

    def start(
        self, ns: str, args: list[str], log: IO[str], pipe_stderr: bool, **extra_env: str
    ) -> subprocess.Popen:
        """python ARGS in namespace ns; output to log, stderr to a pipe if pipe_stderr."""
        proc = subprocess.Popen(
            ['ip', 'netns', 'exec', ns, sys.executable, *args],  # ip execs: the pid is python's
            env=dict(self.env, **extra_env),
            stdout=log,
            stderr=subprocess.PIPE if pipe_stderr else subprocess.STDOUT,
            text=True,
            start_new_session=True,
        )
        self.procs.append(proc)
        return proc

    def link(self, up: bool) -> None:
        _must(ip('-n', self.drive, 'link', 'set', self.drive_dev, 'up' if up else 'down'))

    def received_by_drive(self) -> int:
        """Bytes the drive host's end of the link has received."""
        stats = Path(f'/sys/class/net/{self.drive_dev}/statistics/rx_bytes')
        result = subprocess.run(
            ['ip', 'netns', 'exec', self.drive, 'cat', str(stats)],
            capture_output=True,
            text=True,
            timeout=30,
        )
        _must(result)
        return int(result.stdout)

    def remove(self) -> None:
        """SIGINT to what this test started, SIGKILL after 10 s and to anything else left in
        the namespaces (their children); then delete the namespaces."""
        for proc in self.procs:
            if proc.poll() is None:
                proc.send_signal(signal.SIGINT)
        for proc in self.procs:
            try:
                proc.communicate(timeout=10)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.communicate()
        for ns in self.created:
            for pid in ip('netns', 'pids', ns).stdout.split():
                with contextlib.suppress(ProcessLookupError):
                    os.kill(int(pid), signal.SIGKILL)
            ip('netns', 'del', ns)
        self.created = [ns for ns in self.created if ns in ip('netns', 'list').stdout.split()]


@contextlib.contextmanager
def two_hosts(env: dict[str, str]) -> Iterator[TwoHosts]:
    """A pair of namespaces for one test; skips the test where none can be made."""
    try:
        with TwoHosts(env) as two:
            yield two
    except NamespacesUnavailable as exc:
        pytest.skip(f'network namespaces cannot be created here: {exc}')
    assert not two.created, f'namespaces left behind: {two.created}'


def wait_for_progress(runner: subprocess.Popen, lines: list[str]) -> None:
    """Read the runner's stderr until its first progress line: the job is under way."""
    assert runner.stderr is not None
    for line in runner.stderr:
        lines.append(line)
        if re.match(r'\s*[0-9.]+ / [0-9.]+ s', line):
            return
    raise AssertionError('the runner ended before the job started:\n' + ''.join(lines[-20:]))


def finish(proc: subprocess.Popen, lines: list[str], timeout: float) -> int:
    """The rest of the runner's stderr and its exit code; killed after timeout."""
    assert proc.stderr is not None
    timer = threading.Timer(timeout, proc.kill)
    timer.start()
    try:
        lines.extend(proc.stderr)
        return proc.wait()
    finally:
        timer.cancel()
