"""What `ros2 launch mill_bringup scenario.launch.py` starts, decided without `launch`. ROS-free.

The launch file (launch/scenario.launch.py) is a thin adapter: it declares ARGUMENTS and
turns the plan of `plan()` into launch_ros Node actions, so that everything it decides is
tested here without a ROS install that has `launch`:

- scenario: a name in config/ or a scenario file; its `mill_scenario` entry lists the nodes;
- namespace: the machine namespace of every node (default: the scenario's, else the root);
- params_file: a ROS 2 parameter file applied on top of the scenario; its entries are keyed
  `/**`, `NAME`, `/NAME` or `/**/NAME` and must name nodes of the scenario;
- timing: `lockstep` or `realtime`, set as `run_scenario --timing` sets it (every node's
  `timing`; realtime also no sim time and one sample of command delay) (empty:
  what the scenario says);
- log_level: every node's `--log-level`;
- layout: which nodes share a process (mill_bringup.layout: processes, per_axis, single;
  empty: what the scenario says). Nodes that share one run in `mill_container`, which gets
  the same namespace, parameter file and arguments; each node keeps its name;
- private_clock: `true` remaps /clock to NAMESPACE/clock for every node of the launch, as
  `run_scenario --private-clock` does, so that two simulated machines launched in one
  domain under two namespaces each keep their own clock; it needs a namespace (empty: the
  scenario's `private_clock`);
- end_with_job: `false` keeps the machine up once the job is done (timing realtime only):
  the trajectory holds the job's last point under control and takes jog, home and MDI
  (mill_trajectory.manual) until Ctrl-C; no job_watch is started.

Every node gets one parameter file (written by `write_parameters`) with its merged values
keyed `/**/NAME`, so they apply under the namespace whatever the keys of the scenario and
of params_file, and the scenario's `mill_scenario: launch:` list, from which mill_container
learns what each of its nodes is. The node that clocks the job (plant or force process) is
required: its exit ends the launch with its exit code. The `job_watch` node ends the launch
when the trajectory reports the job done. The `machine_view` node publishes the job's URDF
(mill_bringup.machine_model) and the tool trace; robot_state_publisher, given the same URDF
and the namespace as its `frame_prefix`, is started where it is installed (it is not on
PyPI), else the plan says so in a note the launch prints at INFO.
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mill_common.machine_urdf import frame_prefix

from mill_bringup.cli import set_timing
from mill_bringup.layout import Process
from mill_bringup.layout import processes as layout_processes
from mill_bringup.machine_model import VIEW_NODE, view_parameters
from mill_bringup.scenario import (
    LAYOUTS,
    SCENARIO_KEY,
    NodeLaunch,
    Scenario,
    ScenarioError,
    apply_params_file,
    check_layout,
    dump_parameters,
    load,
)
from mill_common import topics

if TYPE_CHECKING:  # the job's modules load only when a plan is made
    from mill_bringup.job_config import JobConfig

TIMINGS = ('lockstep', 'realtime')
LOG_LEVELS = ('debug', 'info', 'warn', 'error', 'fatal')
SWITCHES = {'true': True, 'false': False, '': None}  # a boolean argument; '': the scenario's
# The node that ends the launch once the job is done (mill_bringup.job_watch).
JOB_WATCH = NodeLaunch('job_watch', 'mill_bringup', 'job_watch')
# The node that publishes the URDF and the tool trace (mill_bringup.machine_view), and the
# one that makes /tf of them where it is installed (it is not on PyPI).
MACHINE_VIEW = NodeLaunch(VIEW_NODE, 'mill_bringup', 'machine_view')
STATE_PUBLISHER = NodeLaunch(
    'robot_state_publisher', 'robot_state_publisher', 'robot_state_publisher'
)


def installed(package: str) -> bool:
    """Whether a ROS package is in the ament index of this environment."""
    try:
        from ament_index_python.packages import get_package_prefix

        get_package_prefix(package)
    except (LookupError, OSError, ImportError):  # not found, no index at all
        return False
    return True


@dataclass(frozen=True)
class Argument:
    """A launch argument, declared once: the launch file declares it (its description is
    what `--show-args` prints) and docs_params writes the user guide's table of it."""

    name: str
    default: str
    description: str
    empty: str = 'none'  # what an empty default stands for, as the user guide says it


ARGUMENTS = (
    Argument(
        'scenario',
        'slotting',
        'scenario name (`config/NAME.yaml`) or path to a scenario file; its `mill_scenario` '
        'entry lists the nodes',
    ),
    Argument(
        'namespace',
        '',
        'machine namespace of every node, e.g. `machine2`; `/diagnostics` stays global, and '
        '`/clock` unless `private_clock` is true',
        "the scenario's, else `/`",
    ),
    Argument(
        'params_file',
        '',
        'ROS 2 parameter file applied on top of the scenario; entries `/**` (or another '
        'wildcard such as `/**/x_*`) give each name to the nodes that declare it; `NODE`, '
        '`/NODE` or `/**/NODE` must name a node of the scenario and hold only names it declares',
    ),
    Argument(
        'timing',
        '',
        '`lockstep` or `realtime`, given to every node as its `timing` parameter, as '
        '`run_scenario --timing` sets it',
        "the scenario's",
    ),
    Argument('log_level', 'info', '`--log-level` of every node: ' + ', '.join(LOG_LEVELS)),
    Argument(
        'layout',
        '',
        'which nodes share a process: ' + ', '.join(f'`{x}`' for x in LAYOUTS) + '; the nodes '
        'a layout puts together run in one `mill_container` process and keep their names, '
        'parameters and topics',
        "the scenario's, else `processes`",
    ),
    Argument(
        'private_clock',
        '',
        '`true`: every node of the launch has `/clock` remapped to `NAMESPACE/clock`, as '
        '`run_scenario --private-clock` does, so that two simulated machines launched side '
        'by side in one domain each step to their own plant; needs a `namespace`',
        "the scenario's, else off",
    ),
    Argument(
        'end_with_job',
        'true',
        '`false`: the launch does not end when the job is done; the machine stays under '
        "control at the job's last point for jog, home and MDI (`~/jog`, `~/home`, `~/mdi` "
        'of the trajectory) until Ctrl-C; timing realtime only (in lockstep nothing steps '
        'once the job is done)',
    ),
)
# What runs the nodes a layout puts together (mill_bringup.container).
CONTAINER_PACKAGE = 'mill_bringup'
CONTAINER_EXECUTABLE = 'mill_container'


@dataclass(frozen=True)
class NodePlan:
    """One process to start: what launch_ros.actions.Node gets. A container (nodes not
    empty) is started without a node name: its nodes, given as arguments, keep theirs."""

    package: str
    executable: str
    name: str  # the node's name; for a container, the process's
    namespace: str
    parameters: list[str]  # parameter files, in order
    remappings: list[tuple[str, str]]
    ros_arguments: list[str]
    required: bool  # its exit ends the launch
    nodes: tuple[str, ...] = ()  # a container's nodes


@dataclass
class Plan:
    scenario: Scenario
    nodes: list[NodePlan] = field(default_factory=list)
    parameters: dict[str, Any] = field(default_factory=dict)  # the file every node gets
    config: JobConfig | None = None  # the job's configuration, checked (job_config)
    notes: list[str] = field(default_factory=list)  # INFO lines for the launch to print


def plan(
    scenario: str,
    namespace: str = '',
    params_file: str = '',
    timing: str = '',
    log_level: str = 'info',
    layout: str = '',
    private_clock: str = '',
    end_with_job: str = 'true',
    *,
    found: Callable[[str], bool] = installed,
) -> Plan:
    """The nodes a launch of this scenario starts; ScenarioError (one line) for bad input.
    `found(package)` says whether a package outside mill is installed."""
    from mill_bringup.jobs.registry import job_for
    from mill_bringup.machine_model import robot_description

    scen = load(scenario)
    if namespace:
        scen.set_namespace(namespace)
    if params_file:
        apply_params_file(scen, params_file)
    if timing:
        if timing not in TIMINGS:
            raise ScenarioError(f'timing must be one of {", ".join(TIMINGS)}, got {timing!r}')
        set_timing(scen, timing)  # what run_scenario --timing sets, the same way
    if log_level not in LOG_LEVELS:
        raise ScenarioError(f'log_level must be one of {", ".join(LOG_LEVELS)}, got {log_level!r}')
    if private_clock.lower() not in SWITCHES:
        raise ScenarioError(f'private_clock must be true or false, got {private_clock!r}')
    switch = SWITCHES[private_clock.lower()]
    if switch is not None:
        scen.private_clock = switch
    ends = SWITCHES.get(end_with_job.lower(), 'bad')
    if ends not in (True, False):
        raise ScenarioError(f'end_with_job must be true or false, got {end_with_job!r}')
    if scen.private_clock and scen.namespace == topics.ROOT:
        raise ScenarioError('a private clock needs a namespace (namespace:=NAME)')
    # The job's configuration: every value and cross-node rule checked before anything
    # starts, and the graph (exactly one clock node).
    job = job_for(scen)
    if not ends and job.config.timing != 'realtime':
        raise ScenarioError(
            'end_with_job:=false needs timing realtime (in lockstep nothing steps once the job '
            'is done)'
        )
    chosen = check_layout(layout) if layout else scen.layout
    job.prepare_graph(monitored=False, layout=chosen)  # what the layout changes (no monitor)
    clocks = {n.name for n in job.clock_nodes}
    remappings = []
    if scen.private_clock and scen.namespace != topics.ROOT:
        remappings.append((topics.CLOCK, topics.clock(scen.namespace, private=True)))
    # What mill_container reads to tell which class each of its nodes is (the runner gives
    # it the scenario file itself).
    launch = [f'{n.name} {n.package} {n.executable}' for n in scen.nodes]
    entry = {SCENARIO_KEY: {'ros__parameters': {'launch': launch}}}
    out = Plan(scen, parameters={**entry, **scen.node_parameters()}, config=job.config)
    # The viewers' nodes: the URDF of this job's machine, and /tf of it where possible.
    urdf = robot_description(job.config)
    views = [MACHINE_VIEW]
    out.parameters.update(view_parameters(job.config))
    if found(STATE_PUBLISHER.package):
        views.append(STATE_PUBLISHER)
        out.parameters[f'/**/{STATE_PUBLISHER.name}'] = {
            'ros__parameters': {
                'robot_description': urdf,
                'frame_prefix': frame_prefix(scen.namespace),
            }
        }
    else:
        out.notes.append(
            'robot_state_publisher is not installed: no /tf of the machine (the URDF is on '
            f'{topics.qualify(topics.ROBOT_DESCRIPTION, scen.namespace)})'
        )
    processes = layout_processes(scen, chosen, config=job.config)
    watch = (JOB_WATCH,) if ends else ()
    extra = [Process(n.name, (n,)) for n in (*watch, *views)]
    for process in [*processes, *extra]:
        first = process.nodes[0]
        out.nodes.append(
            NodePlan(
                package=CONTAINER_PACKAGE if process.container else first.package,
                executable=CONTAINER_EXECUTABLE if process.container else first.executable,
                name=process.name,
                namespace=scen.namespace,
                parameters=[],  # filled by write_parameters
                remappings=list(remappings),
                ros_arguments=['--log-level', log_level],
                required=bool(clocks & set(process.node_names)) or first is JOB_WATCH,
                nodes=tuple(process.node_names) if process.container else (),
            )
        )
    return out


def write_parameters(p: Plan, directory: str | None = None) -> Path:
    """Write the plan's parameter file and give it to every node; returns its path."""
    folder = Path(directory or tempfile.mkdtemp(prefix='mill_launch_'))
    path = folder / f'{p.scenario.name}_parameters.yaml'
    path.write_text(dump_parameters(p.parameters))
    for node in p.nodes:
        node.parameters.clear()
        node.parameters.append(str(path))
    return path


def exit_code(returncode: int) -> int:
    """A process's return code as a shell reports it (killed by signal N: 128 + N)."""
    return 128 - returncode if returncode < 0 else min(returncode, 255)
