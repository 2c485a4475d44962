"""Trajectory registry: the `trajectory` parameter value -> class."""

from __future__ import annotations

from mill_common.registry import Registry

from mill_trajectory.base import Trajectory
from mill_trajectory.bezier import BezierRestToRest
from mill_trajectory.gcode_program import GcodeTrajectory
from mill_trajectory.linear_path import LinearPath
from mill_trajectory.program import ProgramTrajectory
from mill_trajectory.sinusoid import Sinusoid

TRAJECTORIES: Registry[Trajectory] = Registry(
    'trajectory',
    {
        'linear': LinearPath,  # Beltrán 2013 eq. (19)-(22)
        'bezier': BezierRestToRest,  # Chávez-Conde, 8th-order rest-to-rest
        'sinusoid': Sinusoid,  # Maharof 2018 reference
        'program': ProgramTrajectory,  # program of segments from the scenario file
        'gcode': GcodeTrajectory,  # a G-code part program, planned within the machine's limits
    },
)
