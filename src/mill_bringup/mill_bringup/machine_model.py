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
