"""Topic names of the hardware contract (see the README's topic table). ROS-free."""

from __future__ import annotations

REFERENCE = '/mill/reference'
CUTTING_FORCE = '/mill/cutting_force'
GROUND_TRUTH = '/mill/ground_truth'
FEED_OVERRIDE = '/mill/feed_override'
# The force between samples (force-process plant: the sensor stream on a fine grid).
CUTTING_FORCE_TRACE = '/mill/cutting_force/trace'
# Force controller: force used, reference, feed command, override, active β, depth.
FORCE_CONTROL_STATE = '/mill/force_control/state'
CLOCK = '/clock'
DIAGNOSTICS = '/diagnostics'


def state(axis: str) -> str:
    """Measured position of one axis (plant or hardware driver publishes)."""
    return f'/mill/{axis}/state'


def joint_command(axis: str) -> str:
    """Motor torque command of one axis (its controller publishes)."""
    return f'/mill/{axis}/joint_command'


def estimate(axis: str) -> str:
    """Observer output of one axis."""
    return f'/mill/{axis}/estimate'


def controller_state(axis: str) -> str:
    """Internal state of an axis controller that has one (adaptive PI: estimates, gains)."""
    return f'/mill/{axis}/controller_state'


def observer_state(axis: str) -> str:
    """Internal state of an observer that has one (rls: the identified model)."""
    return f'/mill/{axis}/observer_state'
