"""One realtime run at one rate: the hardware case in one layout, or its floor.

- `hardware`: the drive in its own process (mill_bench.drive_process), the rest of the graph
  in the layout, run by the runner with the drive as an external node (`run_scenario
  --external plant`): the runner activates it once the graph is up.
- `floor`: the same drive, at the same rate, against an echo node (mill_bench.echo) that
  answers each state at once, and the same listener as the runner's (its monitor, in this
  process): what transport and executor allow the loop, none of our nodes' work in it.

Both give a RatePoint (mill_bench.realtime_figures): the drive's own figures from its
`plant: realtime` status, the latency per hop as the listener received the messages
(mill_bench.hops) and the CPU per tick of the drive and of the rest (graph and runner, or
echo and listener). A run that fails raises RunError or GraphError.
"""

from __future__ import annotations

import contextlib
import math
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from mill_bringup.graph import cpu_seconds
from mill_bringup.jobs.realtime import drive_ticks
from mill_bringup.lifecycle_client import activate
from mill_bringup.runner.options import RunError, RunOptions
from mill_bringup.runner.run import run
from mill_bringup.runner.session import Session
from mill_bringup.scenario import Scenario
from mill_common.env import ros_environment

from mill_bench import echo, hops
from mill_bench.drive_process import HopTimedJob, drive_node, drive_process
from mill_bench.realtime_figures import FLOOR, RatePoint
from mill_common import topics

if TYPE_CHECKING:
    from mill_bringup.monitor import Monitor

READY_TIMEOUT = 60.0  # [s] for the echo node to be discovered
STATUS_TIMEOUT = 3.0  # [s] for the drive's next status (it reports once a second)


def hardware(scen: Scenario, layout: str, rate: float, run_dir: Path, domain_id: str) -> RatePoint:
    """The scenario (mill_bench.drive_process.realtime_scenario) in `layout`, its drive apart."""
    env = ros_environment(domain_id=domain_id)
    with drive_process(scen, run_dir / 'drive', env) as drive:
        job = HopTimedJob(scen, drive.cpu)
        options = RunOptions(
            quiet=True, domain_id=domain_id, external=frozenset({drive.name}), layout=layout
        )
        result = run(job, run_dir / 'graph', options)
    return job.point(
        layout,
        rate,
        job.drive_cpu_ms_per_tick(),
        result.cpu_ms_per_step,
        [f.text() for f in result.failures],
    )


@contextlib.contextmanager
def echo_process(
    axes: Sequence[str], env: dict[str, str], log: Path, limit: float
) -> Iterator[subprocess.Popen[bytes]]:
    """The echo node (mill_bench.echo) while inside `with`."""
    command = [sys.executable, '-m', 'mill_bench.echo', *axes, '--limit', f'{limit:g}']
    with open(log, 'w') as out:
        proc = subprocess.Popen(
            command, env=env, stdout=out, stderr=subprocess.STDOUT, start_new_session=True
        )
    try:
        yield proc
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def floor(scen: Scenario, rate: float, duration: float, run_dir: Path, domain_id: str) -> RatePoint:
    """The scenario's drive against the echo node for `duration` s after its activation."""
    env = ros_environment(domain_id=domain_id)
    run_dir.mkdir(parents=True, exist_ok=True)
    scen.add_override(f'{drive_node(scen)}.command_owners={[echo.NAME] * 3!r}')  # x, y, z
    with drive_process(scen, run_dir / 'drive', env) as drive:
        job = HopTimedJob(scen, drive.cpu)
        limit = duration + 2 * READY_TIMEOUT  # never outlives a lost run
        with (
            Session(
                job, run_dir / 'listener', RunOptions(quiet=True, domain_id=domain_id), []
            ) as session,
            echo_process(job.axes, env, run_dir / 'echo.log', limit) as proc,
        ):

            def spin(when: str) -> None:
                session.spin(when)
                drive.graph.check(when)
                if proc.poll() is not None:
                    raise RunError(f'the echo node exited with code {proc.returncode} {when}')

            def cpu() -> tuple[float, float]:  # the drive's, and the echo's and listener's
                return drive.cpu(), cpu_seconds(proc.pid) + time.process_time()

            monitor = session.monitor
            _wait_for_echo(monitor, job.axes, spin)
            activate(monitor, session.executor, drive.name, session.progress, _never, READY_TIMEOUT)
            _wait_for_answers(monitor, job.axes, spin)
            cpu_at = [cpu()]
            end = time.monotonic() + duration
            while time.monotonic() < end:
                spin('while the floor ran')
            # The drive's figures count from its activation: its first status after the run.
            job.drive = _next_status(monitor, job.drive_status, spin)
            cpu_at.append(cpu())
            job.hops = hops.hop_latencies(
                hops.timed_messages(monitor, job.timed_topics()), job.axes
            )
    ticks = drive_ticks(job.drive)[1]
    per_tick = [1e3 * (b - a) / ticks if ticks else math.nan for a, b in zip(*cpu_at, strict=True)]
    return job.point(FLOOR, rate, per_tick[0], per_tick[1], ())


def _never() -> bool:
    return False  # the floor's drive never starts by itself: it waits to be activated


def _wait_for_echo(monitor: Monitor, axes: Sequence[str], spin: Callable[[str], None]) -> None:
    """Until the listener sees the echo's command publishers and its state subscriptions."""
    deadline = time.monotonic() + READY_TIMEOUT
    while not all(
        monitor.count_publishers(topics.joint_command(a)) >= 1
        and monitor.count_subscribers(topics.state(a)) >= 2  # the echo's and the listener's
        for a in axes
    ):
        if time.monotonic() > deadline:
            raise RunError(f'the echo node was not discovered within {READY_TIMEOUT:g} s')
        spin('before the floor started')


def _wait_for_answers(monitor: Monitor, axes: Sequence[str], spin: Callable[[str], None]) -> None:
    """Until the echo has answered on every axis: the drive counts an axis's ticks from its
    first command, so on a busy machine the window measured starts once they all count."""
    deadline = time.monotonic() + READY_TIMEOUT
    while not all(monitor.messages(topics.joint_command(a)) for a in axes):
        if time.monotonic() > deadline:
            raise RunError(f'the echo node did not answer within {READY_TIMEOUT:g} s')
        spin('before the floor ran')


def _next_status(monitor: Monitor, name: str, spin: Callable[[str], None]) -> dict[str, str]:
    """The first status `name` the listener hears from now on."""
    before = monitor.status(name)
    deadline = time.monotonic() + STATUS_TIMEOUT
    while (status := monitor.status(name)) is None or status == before:
        if time.monotonic() > deadline:
            raise RunError(f'no status {name!r} within {STATUS_TIMEOUT:g} s')
        spin('while the floor ended')
    return status
