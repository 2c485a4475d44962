"""Trajectory registry: the `trajectory` parameter value -> class."""

from __future__ import annotations

from mill_trajectory.linear_path import LinearPath

TRAJECTORIES: dict[str, type] = {
    'linear': LinearPath,
}
