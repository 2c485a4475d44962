"""The node processes of a scenario: launch, supervise, stop.

A node alone in its process runs as `ros2 run` would start it (`python -m MODULE --ros-args
-r __node:=NAME [-r __ns:=NAMESPACE] --params-file SCENARIO --params-file PARAMETERS`); the
nodes a layout puts together (mill_bringup.layout) run in one container process
(`python -m mill_bringup.container NAME ... --ros-args ...`, the same arguments). Each
process runs in its own session, with its output in RUN_DIR/logs/PROCESS.log.
RUN_DIR/parameters.yaml holds every node's values with the overrides, keyed `/**/NAME` so
that they apply under the graph's namespace too. A process dies with the one that started
it, whatever ends that process (Linux PR_SET_PDEATHSIG, set in the child before exec; a
child whose parent is already gone by then ends at once): a killed runner never leaves a
graph running on its own. The signal follows the thread that started the process: launch
from the main thread.

Beside the graph, processes that only watch it (`launch_beside`: machine_view for
run_scenario --view) run in the same namespace and domain with the same remappings, their
parameters in RUN_DIR/NAME.yaml and output in RUN_DIR/logs/NAME.log; they are stopped with the
graph, but neither supervised (a viewer that ends does not end the job) nor counted in the
run's CPU time and memory.
"""

from __future__ import annotations

import ctypes
import functools
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from mill_common.executable import hold_stop_signals

from mill_bringup.layout import Process
from mill_bringup.scenario import Scenario, dump_parameters

PR_SET_PDEATHSIG = 1


CONTAINER_MODULE = 'mill_bringup.container'


class GraphError(RuntimeError):
    """A node of the graph ended or never appeared; str() says which and why."""


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of a live process [s] (/proc/PID/stat), 0 if unreadable."""
    try:
        fields = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')
    except (OSError, IndexError, ValueError):
        return 0.0


def vm_hwm_mb(pid: int) -> float:
    """Peak resident memory of a live process [MB] (VmHWM), NaN if unreadable."""
    try:
        for line in Path(f'/proc/{pid}/status').read_text().splitlines():
            if line.startswith('VmHWM:'):
                return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return float('nan')


def pss_mb(pid: int | str = 'self') -> float:
    """Proportional set size of a live process [MB]: its resident memory with each page
    shared among processes (libraries) divided among them; NaN if unreadable. Unlike the RSS,
    the PSS of several processes adds up to the memory they use together."""
    try:
        for line in Path(f'/proc/{pid}/smaps_rollup').read_text().splitlines():
            if line.startswith('Pss:'):
                return int(line.split()[1]) / 1024.0
    except (OSError, ValueError, IndexError):
        pass
    return float('nan')


def _child_setup(parent: int) -> None:
    """In the child before exec: SIGINT and SIGTERM held until the node can handle them
    (mill_common.executable), and SIGTERM when the parent dies (Linux; elsewhere nothing)."""
    hold_stop_signals()
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGTERM)
    except (OSError, AttributeError):
        return
    if os.getppid() != parent:  # the parent died between fork and prctl: no signal will come
        os._exit(1)


class Graph:
    """The scenario's processes (a node alone, or a container of several), keyed by name."""

    def __init__(
        self,
        scen: Scenario,
        run_dir: Path,
        env: dict[str, str],
        respawn: Iterable[str] = (),
        max_restarts: int = 3,
    ) -> None:
        self.scen = scen
        self.procs: dict[str, subprocess.Popen[bytes]] = {}
        self.processes: dict[str, Process] = {}
        # Processes started again when they die (ros2 launch's respawn), up to max_restarts.
        self.respawn = set(respawn)
        self.max_restarts = max_restarts
        self.restarts: dict[str, int] = {}
        self.last_restart: float | None = None  # time.monotonic() of the newest restart
        self.notes: list[str] = []
        self.logs: dict[str, Path] = {}
        self._log_dir = run_dir / 'logs'
        self._log_dir.mkdir(parents=True, exist_ok=True)
        self._parameters = run_dir / 'parameters.yaml'
        self._run_dir = run_dir
        self._env = env
        self.beside: dict[str, subprocess.Popen[bytes]] = {}  # launch_beside

    def node_names(self) -> set[str]:
        """The nodes of every process launched."""
        return {name for p in self.processes.values() for name in p.node_names}

    def command(self, process: Process) -> list[str]:
        """How this process is started: a node's module, or the container with its nodes."""
        if process.container:
            start = [CONTAINER_MODULE, *process.node_names, '--ros-args']
        else:
            (node,) = process.nodes
            start = [
                node.kind.module,
                '--ros-args',
                '-r',
                f'__node:={node.name}',
            ]
        remaps = [arg for rule in self.scen.remappings() for arg in ('-r', rule)]
        return [
            sys.executable,
            '-m',
            *start,
            *remaps,
            '--params-file',
            str(self.scen.path),
            '--params-file',
            str(self._parameters),
        ]

    def beside_command(self, name: str, module: str) -> list[str]:
        """How a process beside the graph is started: node `name` of `module`, in the
        graph's namespace with its remappings, its parameters from RUN_DIR/NAME.yaml."""
        remaps = [arg for rule in self.scen.remappings() for arg in ('-r', rule)]
        params = self._run_dir / f'{name}.yaml'
        return [
            *(sys.executable, '-m', module, '--ros-args', '-r', f'__node:={name}'),
            *remaps,
            *('--params-file', str(params)),
        ]

    def launch_beside(self, name: str, module: str, parameters: dict[str, Any]) -> None:
        """Start node `name` of `module` beside the graph (see the module doc) with these
        parameter file entries."""
        (self._run_dir / f'{name}.yaml').write_text(dump_parameters(parameters))
        with open(self._log_dir / f'{name}.log', 'w') as log:
            self.beside[name] = subprocess.Popen(
                self.beside_command(name, module),
                stdout=log,
                stderr=subprocess.STDOUT,
                env=self._env,
                start_new_session=True,
                preexec_fn=functools.partial(_child_setup, os.getpid()),
            )

    def launch(self, processes: Iterable[Process]) -> None:
        """Start these processes of the scenario's nodes."""
        # Written at each launch: the job may have adjusted the scenario since the last one.
        self._parameters.write_text(dump_parameters(self.scen.node_parameters()))
        for process in processes:
            cmd = self.command(process)
            again = process.name in self.procs
            self.processes[process.name] = process
            self.logs[process.name] = self._log_dir / f'{process.name}.log'
            with open(self.logs[process.name], 'a' if again else 'w') as log:
                self.procs[process.name] = subprocess.Popen(
                    cmd,
                    stdout=log,
                    stderr=subprocess.STDOUT,
                    env=self._env,
                    start_new_session=True,
                    preexec_fn=functools.partial(_child_setup, os.getpid()),
                )

    def exited(self) -> dict[str, int]:
        return {n: p.returncode for n, p in self.procs.items() if p.poll() is not None}

    def restarted_nodes(self) -> dict[str, int]:
        """How often each node was started again (a container's nodes with their process)."""
        return {n: c for p, c in self.restarts.items() for n in self.processes[p].node_names}

    def what(self, name: str) -> str:
        """A process as messages name it: `node NAME`, or `process NAME (nodes A, B)`."""
        process = self.processes[name]
        if not process.container:
            return f'node {name}'
        return f'process {name} (nodes {", ".join(process.node_names)})'

    def check(self, when: str) -> None:
        """Start a respawned process again; GraphError naming any other one that has exited."""
        for name, code in self.exited().items():
            count = self.restarts.get(name, 0)
            if name in self.respawn and count < self.max_restarts:
                self.restarts[name] = count + 1
                self.notes.append(
                    f'{self.what(name)} exited with code {code} {when}: started again'
                )
                self.launch([self.processes[name]])
                self.last_restart = time.monotonic()
                continue
            raise GraphError(
                f'{self.what(name)} exited with code {code} {when}:\n' + self.log_tail(name)
            )

    def cpu(self) -> float:
        """CPU seconds used so far by the node processes and this process."""
        return sum(self.cpu_by_process().values())

    def cpu_by_process(self) -> dict[str, float]:
        """CPU seconds used so far by each node process and by this one ('runner')."""
        used = {n: cpu_seconds(p.pid) for n, p in self.procs.items()}
        return used | {'runner': time.process_time()}

    def pss(self) -> float:
        """Memory the node processes and this one use together now (sum of PSS) [MB]."""
        live = [p.pid for p in self.procs.values() if p.poll() is None]
        return sum(pss_mb(pid) for pid in live) + pss_mb()

    def peak_rss(self) -> dict[str, float]:
        return {n: vm_hwm_mb(p.pid) for n, p in self.procs.items() if p.poll() is None}

    def log_tail(self, name: str, lines: int = 6) -> str:
        try:
            text = self.logs[name].read_text().strip().splitlines()
        except OSError:
            return ''
        return '\n'.join('    ' + t for t in text[-lines:])

    def stop(self, grace: float = 5.0) -> None:
        """SIGINT to every node and every process beside the graph; SIGKILL to the process
        group of any still alive after grace."""
        every = [*self.procs.values(), *self.beside.values()]
        for p in every:
            if p.poll() is None:
                p.send_signal(signal.SIGINT)
        deadline = time.monotonic() + grace
        for p in every:
            try:
                p.wait(max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()
