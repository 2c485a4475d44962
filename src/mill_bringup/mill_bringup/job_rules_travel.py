"""The job's rules on the machine's travel (mill_bringup.job_config): every axis within its
following-error band stays inside the travel, and the trajectory's travel lies inside the
drive's. ROS-free.
"""

from __future__ import annotations

import math

from mill_common.signals import AXES

from mill_bringup.catalogue import CONTROLLER
from mill_bringup.job_config_types import Failure, JobConfig, Side


def following_band(c: JobConfig) -> list[Failure]:
    """Every axis, anywhere within its following-error limit of the path, stays inside the
    machine's travel (the trajectory's travel.min / travel.max): a controller trips only
    beyond that limit, so the whole band must fit, as before an identify run."""
    if c.plant is None or c.trajectory is None:
        return []
    trajectory = c.trajectory
    tv = c.node(trajectory).values
    limits: dict[int, Side] = {}
    for n in c.of_role(CONTROLLER):
        i = AXES.index(n.values['axis'])
        limits[i] = Side(n.name, 'following_error_limit', float(n.values['following_error_limit']))
    lo, hi = c.trajectory_job().trajectory.bounds(tv['sample_period'])
    out = []
    for i, axis in enumerate(AXES):
        limit = limits.get(i, Side(trajectory, 'path', 0.0))
        b = limit.value if math.isfinite(limit.value) else 0.0
        for edge, sign, end, side in (
            (lo[i], -1.0, tv['travel.min'][i], 'min'),
            (hi[i], 1.0, tv['travel.max'][i], 'max'),
        ):
            if sign * (edge + sign * b - end) > 0.0:
                travel = Side(trajectory, f'travel.{side} ({axis})', end)
                out.append(
                    Failure(
                        'following_band',
                        (limit, travel),
                        f'scenario {c.scenario}: axis {axis} may leave the machine travel '
                        f'before its controller trips: its path reaches {edge:.6g} m and its '
                        f'following-error limit is {1e3 * b:g} mm ({limit.node}), beyond '
                        f"travel.{side} {end:g} m ({trajectory}'s); move the axis or lower "
                        'the limit',
                    )
                )
    return out


def travel_inside(c: JobConfig) -> list[Failure]:
    """The trajectory's travel (which the path is checked against) lies inside the drive's
    (which its motion guard keeps every axis in): both are the machine's travel, declared
    once (mill_common.travel); the drive's may only be the wider."""
    if c.plant is None or c.trajectory is None:
        return []
    pv, tv = c.node(c.plant).values, c.node(c.trajectory).values
    if 'travel.min' not in pv:  # a plant without a drive's guard (the force process)
        return []
    out = []
    for i, axis in enumerate(AXES):
        for side, sign in (('min', -1.0), ('max', 1.0)):
            name = f'travel.{side}'
            path, drive = tv[name][i], pv[name][i]
            if sign * (path - drive) > 0.0:
                out.append(
                    Failure(
                        'travel',
                        (
                            Side(c.trajectory, f'{name} ({axis})', path),
                            Side(c.plant, f'{name} ({axis})', drive),
                        ),
                        f'scenario {c.scenario}: axis {axis}: the trajectory allows {name} '
                        f"{path:g} m ({c.trajectory}) beyond the drive's {drive:g} m "
                        f'({c.plant}), which stops the axis there; give them one travel',
                    )
                )
    return out
