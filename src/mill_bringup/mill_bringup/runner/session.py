"""The runner's side of a run: its monitor node and executor, the node processes, progress.

A context manager: leaving it, however the run ends (done, an error, Ctrl-C), stops every
node process, closes the bag (valid and complete up to its last message), shuts rclpy down
and puts the signal handlers back. SIGINT and SIGTERM only set a flag that `spin` turns
into KeyboardInterrupt: raised inside a callback of the C++ EventsExecutor it would abort
the process (std::terminate) and leave the graph running and the bag unclosed.
"""

from __future__ import annotations

import math
import os
import signal
import sys
import time
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any

from mill_common.env import ros_environment
from mill_common.executable import ignore_stop_signals
from mill_common.progress import Progress

from mill_analysis import bag_meta
from mill_bringup.graph import Graph
from mill_bringup.jobs.base import GraphPlan, Job
from mill_bringup.runner.options import RunError, RunOptions
from mill_common import topics

if TYPE_CHECKING:
    from mill_bringup.monitor import Monitor


class Session:
    """Monitor, executor and graph of one run, made on entering, released on leaving."""

    def __init__(
        self,
        job: Job[Any],
        run_dir: Path,
        options: RunOptions,
        restartable: list[str],
        graph: GraphPlan | None = None,
    ) -> None:
        self.job = job
        # what the monitor hears (default: the job's plan of its graph as it stands)
        self.plan = graph if graph is not None else job.graph_plan()
        self.options = options
        self.run_dir = run_dir
        self.restartable = restartable
        self.env = ros_environment(domain_id=options.domain_id)
        os.environ.update(self.env)
        self.progress = Progress(job.sim_time, quiet=options.quiet)
        self.peak_pss_mb = 0.0  # graph + runner, sampled once a second
        self._next_check = 0.0
        self._previous: dict[int, Any] = {}
        self._stop: list[int] = []  # signals received (install_stop_handlers)
        self._stops_taken = 0  # of those, ending a stay (take_stop)
        # axes the start handshake released (--rearm), with the stop each was latched by
        self.rearmed: dict[str, str] = {}
        # until the first sample (runner.start sets it from --startup-timeout)
        self.startup_deadline = math.inf
        self._never: Any = None
        self._monitor: Monitor | None = None
        self._graph: Graph | None = None
        self._executor: Any = None
        self._refused: list[str] = []  # scheduling the system refused, said once

    @property
    def domain_id(self) -> str:
        return self.env['ROS_DOMAIN_ID']

    @property
    def monitor(self) -> Monitor:
        assert self._monitor is not None, 'inside the session'
        return self._monitor

    @property
    def graph(self) -> Graph:
        assert self._graph is not None, 'inside the session'
        return self._graph

    @property
    def executor(self) -> Any:
        assert self._executor is not None, 'inside the session'
        return self._executor

    def __enter__(self) -> Session:
        import rclpy
        from mill_common.node_main import install_stop_handlers, make_executor
        from rclpy.signals import SignalHandlerOptions
        from rclpy.task import Future

        from mill_bringup.monitor import Monitor, RecordOptions

        job, options = self.job, self.options
        record = None
        if options.record_bag is not None:
            record = RecordOptions(
                Path(options.record_bag),
                sim_time=self.plan.sim_time,
                # what `report` reads it as, and who sends each topic (what it leaves out)
                notes={
                    **bag_meta.bag_notes(job.RECORD.NAME),
                    **bag_meta.owners_note(job.owners(), job.scenario.namespace),
                },
            )
        self._previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
        self._stop = install_stop_handlers()
        try:
            rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
            plan = self.plan
            self._monitor = Monitor(
                plan.kept,
                record,
                plan.recorded,
                namespace=job.scenario.namespace,
                remappings=job.scenario.remappings(),
                timed=plan.timed,
                late=plan.late,
                late_after=plan.late_after,
                steps=plan.steps,
                owners=job.owners(),
            )
            self._executor = make_executor()
            self._executor.add_node(self._monitor)
            self.listen()
            respawn = self.restartable if options.respawn else ()
            self._graph = Graph(job.scenario, self.run_dir, self.env, respawn=respawn)
            self._never = Future()
        except BaseException:
            self.close()
            raise
        return self

    def listen(self) -> None:
        """The listener's threads at its SCHED_FIFO priority, if the run has one; called
        again once the graph runs (the middleware starts threads as it discovers peers)."""
        priority = self.options.runner_priority
        if priority <= 0:
            return
        from mill_common.realtime_setup import listen_at

        for line in listen_at(priority):
            if line not in self._refused:
                self._refused.append(line)
                if self.progress.quiet:  # a refusal is said even in a quiet run
                    print(f'WARNING: {line}', file=sys.stderr, flush=True)
                else:
                    self.progress.note(f'WARNING: {line}')

    def __exit__(
        self,
        kind: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def close(self) -> None:
        """Stop the graph, close the bag, release rclpy (idempotent)."""
        import rclpy
        from mill_common.node_main import release_node

        if self._graph is not None:
            self._graph.stop()
        if self._monitor is not None:
            self._monitor.close_recording()  # on every way out: the bag is closed and valid
        self.progress.close()
        release_node(self._executor, self._monitor)
        self._executor = self._monitor = self._graph = None
        rclpy.try_shutdown()
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)
        self._previous = {}
        if self._stop:
            # A second signal (launch's SIGTERM after its SIGINT) must not interrupt what
            # the runner still writes.
            ignore_stop_signals()

    def take_stop(self) -> None:
        """The stops asked for so far (Ctrl-C, SIGTERM) are the end of the stay after a
        complete job (run_scenario --stay), not an interruption: the run goes on to collect
        (a further one interrupts it)."""
        self._stops_taken = len(self._stop)

    def spin(self, when: str) -> None:
        """Take messages for 50 ms, then check the graph (`when`: for its error message).

        Polling with spin_once(0) costs tens of µs per call even with nothing to take.
        """
        self.executor.spin_until_future_complete(self._never, timeout_sec=0.05)
        if len(self._stop) > self._stops_taken:
            raise KeyboardInterrupt
        recorder = self.monitor.recorder
        if recorder is not None and recorder.error:
            raise RunError(recorder.error)
        self.graph.check(when)
        if time.monotonic() > self._next_check:
            self._next_check = time.monotonic() + 1.0
            self.peak_pss_mb = max(self.peak_pss_mb, self.graph.pss())
            self._check_one_clock()

    def _check_one_clock(self) -> None:
        """RunError when a clock other than this run's own publishes on its /clock.

        Two simulations in one domain would each step to the other's clock ticks. The check
        is repeated while the run goes on, so that two runs started together are caught too.
        An external clock node (a plant on another host) counts as this run's.
        """
        names = self.graph.node_names()
        external = self.options.external
        ours = sum(1 for n in self.job.clock_nodes if n.name in names or n.name in external)
        clock = self.monitor.resolve_topic_name(topics.CLOCK)
        found = self.monitor.count_publishers(clock)
        if found > ours:
            raise RunError(
                f'{clock} has {found} publishers in ROS_DOMAIN_ID={self.domain_id}, this run '
                f'has {ours}: another simulation shares the domain; give each run its own '
                '--domain-id, or run each under its own --namespace with --private-clock'
            )
