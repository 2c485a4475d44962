"""The machine's URDF from a job's own configuration. ROS-free.

The joints' limits are the values the nodes of the job hold (mill_bringup.job_config): the
travel of the trajectory (`travel.min`, `travel.max`), the drive's `speed_limit` and
`max_torque`; a job without one of those nodes (a hardware driver in place of the plant)
gives that node's declared defaults. mill_common.machine_urdf writes the URDF.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from mill_common.machine_urdf import joint_limits, machine_urdf

from mill_bringup.catalogue import PLANT, TRAJECTORY, of_role

if TYPE_CHECKING:
    from mill_bringup.job_config import JobConfig

# The node that publishes the URDF and the tool trace (mill_bringup.machine_view), as the
# launch and `run_scenario --view` start it.
VIEW_NODE = 'machine_view'
VIEW_MODULE = 'mill_bringup.machine_view'


def _values(role: str, config: JobConfig | None) -> dict[str, Any]:
    """A role's declared defaults, with the job's values of its node where it has one."""
    (kind,) = of_role(role)
    values = {name: spec.default for name, spec in kind.parameter_specs()}
    if config is None or not config.names_of(role):
        return values
    return values | config.values(config.names_of(role)[0])


def robot_description(config: JobConfig | None = None) -> str:
    """The URDF of the machine of this job (None: of the declared defaults)."""
    trajectory, plant = _values(TRAJECTORY, config), _values(PLANT, config)
    limits = joint_limits(
        trajectory['travel.min'],
        trajectory['travel.max'],
        plant['speed_limit'],
        plant['max_torque'],
    )
    return machine_urdf(limits)


def view_parameters(config: JobConfig | None = None) -> dict[str, Any]:
    """machine_view's entry of a parameter file, keyed to apply in any namespace: the URDF
    of this job's machine."""
    urdf = robot_description(config)
    return {f'/**/{VIEW_NODE}': {'ros__parameters': {'robot_description': urdf}}}
