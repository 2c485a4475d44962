"""Topic names of the hardware contract (docs/hardware-driver.md). ROS-free.

The contract's names are relative (`mill/x/state`): a node resolves them under its
namespace, so the default namespace gives `/mill/x/state` and a machine started with
`-r __ns:=/machine2` uses `/machine2/mill/x/state`. `/clock` and `/diagnostics` are
absolute and stay global, as ROS tools expect them.

A node's diagnostic statuses carry its namespace as `hardware_id` (`machine_id`), so that
the statuses of several machines on the shared `/diagnostics` can be told apart, and are
named `<node>: <part>` (`status_name`): a reader finds one by its part (`part_of`), whatever
the node is called.
"""

from __future__ import annotations

import re
from collections.abc import Iterable

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
# Every axis of the machine in one sensor_msgs/JointState (position, velocity, effort), as
# RViz, Foxglove and robot_state_publisher read it, at `joint_states_rate` (the drive).
JOINT_STATES = 'joint_states'
CLOCK = '/clock'
DIAGNOSTICS = '/diagnostics'

ROOT = '/'

# Parts of the statuses readers look for: the trajectory's job, the drive's cycle.
JOB_STATUS = 'job'
DRIVE_STATUSES = ('lockstep', 'realtime')
_TOKEN = re.compile(r'[A-Za-z_][A-Za-z0-9_]*')


def status_name(node: str, part: str) -> str:
    return f'{node}: {part}'


def part_of(name: str) -> str:
    """The part a status is about (what follows the node's name)."""
    return name.partition(': ')[2]


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
