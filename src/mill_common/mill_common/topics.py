"""Topic names of the hardware contract (docs/hardware-driver.md). ROS-free.

The contract's names are relative (`mill/x/state`): a node resolves them under its
namespace, so the default namespace gives `/mill/x/state` and a machine started with
`-r __ns:=/machine2` uses `/machine2/mill/x/state`. `/clock` and `/diagnostics` are
absolute and stay global, as ROS tools expect them.

A node's diagnostic statuses carry its namespace twice, so that the statuses of several
machines on the shared `/diagnostics` never merge: as `hardware_id` (`machine_id`), and in
the name, `<node>: <part>` at the root and `<namespace>/<node>: <part>` in a namespace
(`machine_a/x_controller: inputs`), so that a tool keyed on names (diagnostic_aggregator,
rqt_robot_monitor) keeps two machines apart too. `status_name` makes a name and
`parse_status_name` reads one back; a reader finds a status by its part (`part_of`) or by
node and part (`status_key`), whatever the node is called and wherever it runs.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass

REFERENCE = 'mill/reference'
CUTTING_FORCE = 'mill/cutting_force'
GROUND_TRUTH = 'mill/ground_truth'
FEED_OVERRIDE = 'mill/feed_override'
# The force between samples (force-process plant: the sensor stream on a fine grid).
CUTTING_FORCE_TRACE = 'mill/cutting_force/trace'
# Force controller: force used, reference, feed command, override, active β, depth.
FORCE_CONTROL_STATE = 'mill/force_control/state'
# The newest step a lockstep run's recorder holds whole (rosgraph_msgs/Clock): a plant with
# `recorder_window` does not run further ahead of it (mill_bringup.bag_handshake).
RECORDED = 'mill/recorded'
# For the viewers (RViz, Foxglove): the job's programmed path (nav_msgs/Path, transient
# local, the trajectory publishes it once a job is loaded), the measured tool trace
# (nav_msgs/Path, mill_bringup.machine_view), the machine's URDF (std_msgs/String,
# transient local) and the axes' joint states (sensor_msgs/JointState: every axis's position,
# velocity and effort in one message, at the drive's `joint_states_rate`).
PLANNED_PATH = 'mill/planned_path'
TOOL_TRACE = 'mill/tool_trace'
ROBOT_DESCRIPTION = 'robot_description'
JOINT_STATES = 'joint_states'
# What robot_state_publisher gives from them (absolute, as tf2 expects).
TF = '/tf'
TF_STATIC = '/tf_static'
CLOCK = '/clock'
# A machine's private simulation clock, relative to its namespace (NAMESPACE/clock): what
# /clock is remapped to when several simulated machines share a domain (`clock`).
PRIVATE_CLOCK = 'clock'
DIAGNOSTICS = '/diagnostics'

ROOT = '/'

# Parts of the statuses readers look for: the trajectory's job, the drive's cycle.
JOB_STATUS = 'job'
DRIVE_STATUSES = ('lockstep', 'realtime')
_TOKEN = re.compile(r'[A-Za-z_][A-Za-z0-9_]*')


@dataclass(frozen=True)
class StatusName:
    """A diagnostic status's name read back: the namespace of the machine ('/' at the root),
    the node's own name and the part the status is about."""

    namespace: str
    node: str
    part: str


def status_name(node: str, part: str, ns: str = ROOT) -> str:
    """The name of the status of node `node` in namespace `ns` about `part`:
    `x_controller: inputs` at the root, `machine_a/x_controller: inputs` in /machine_a."""
    prefix = namespace(ns).strip('/')
    return f'{prefix}/{node}: {part}' if prefix else f'{node}: {part}'


def parse_status_name(name: str) -> StatusName:
    """What `status_name` put into a name (a name without ': ' is a node's, with no part)."""
    qualified, _, part = name.partition(': ')
    ns, _, node = qualified.rpartition('/')
    return StatusName('/' + ns.strip('/'), node, part)


def part_of(name: str) -> str:
    """The part a status is about (what follows the node's name)."""
    return parse_status_name(name).part


def status_key(name: str) -> tuple[str, str]:
    """(node, part) of a status name, without its namespace: how a reader that has already
    kept its machine's statuses (by hardware_id, `from_machine`) finds one."""
    parsed = parse_status_name(name)
    return parsed.node, parsed.part


def state(axis: str) -> str:
    """Measured position of one axis (plant or hardware driver publishes)."""
    return f'mill/{axis}/state'


def joint_command(axis: str) -> str:
    """Motor torque command of one axis (its controller publishes)."""
    return f'mill/{axis}/joint_command'


def estimate(axis: str) -> str:
    """Observer output of one axis."""
    return f'mill/{axis}/estimate'


def controller_state(axis: str) -> str:
    """Internal state of an axis controller that has one (adaptive PI: estimates, gains)."""
    return f'mill/{axis}/controller_state'


def observer_state(axis: str) -> str:
    """Internal state of an observer that has one (rls: the identified model)."""
    return f'mill/{axis}/observer_state'


def namespace(text: str) -> str:
    """A namespace as ROS writes it: '' and '/' are the root, 'machine2' is '/machine2'.

    ValueError (one line) for a name ROS would refuse: tokens of letters, digits and
    underscores, not starting with a digit, separated by single slashes.
    """
    name = text.strip()
    if name in ('', ROOT):
        return ROOT
    tokens = name.strip('/').split('/')
    if name.endswith('/') or not all(_TOKEN.fullmatch(t) for t in tokens):
        raise ValueError(
            f'namespace {text!r} is not valid: use names of letters, digits and _ '
            '(not starting with a digit) separated by /, e.g. machine2 or /shop/machine2'
        )
    return '/' + '/'.join(tokens)


def qualify(name: str, ns: str = ROOT) -> str:
    """The absolute name a node in namespace `ns` gives topic `name` (absolute names stay)."""
    if name.startswith('/'):
        return name
    return f'{namespace(ns).rstrip("/")}/{name}'


def clock(ns: str = ROOT, private: bool = False) -> str:
    """The simulation clock's topic of the machine in namespace `ns`: the global /clock, or
    with a private clock NAMESPACE/clock (a machine at the root has no private clock)."""
    space = namespace(ns)
    return qualify(PRIVATE_CLOCK, space) if private and space != ROOT else CLOCK


def namespaces_with(names: Iterable[str], relative: str) -> list[str]:
    """The namespaces in which `relative` is one of these absolute names, sorted."""
    found = set()
    for name in names:
        if name == '/' + relative:
            found.add(ROOT)
        elif name.endswith('/' + relative) and name.startswith('/'):
            found.add(name[: -len(relative) - 1])
    return sorted(found)


def machine_id(ns: str) -> str:
    """The `hardware_id` of the diagnostic statuses of a node in namespace `ns`."""
    return namespace(ns)


def from_machine(hardware_id: str, ns: str) -> bool:
    """Whether a diagnostic status with this hardware_id belongs to the machine in `ns`.

    A status whose hardware_id is not a namespace (a bag recorded before statuses carried
    one, or another tool's status) belongs to every machine.
    """
    if not hardware_id.startswith('/'):
        return True
    return hardware_id == namespace(ns)
