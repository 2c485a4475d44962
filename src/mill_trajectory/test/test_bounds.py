"""Each path type's box (Trajectory.bounds) holds every sample of its path, and the types
that compute it from their shape give the box the samples give."""

from __future__ import annotations

import numpy as np
import pytest
from mill_trajectory.base import Trajectory
from mill_trajectory.bezier import BezierParams, BezierRestToRest
from mill_trajectory.linear_path import LinearParams, LinearPath
from mill_trajectory.program import ProgramParams, ProgramTrajectory
from mill_trajectory.sinusoid import Sinusoid, SinusoidParams

STEP = 1e-3

PATHS = {
    'linear': LinearPath(
        LinearParams(waypoints=[-0.075, -0.105, -0.005, -0.075, -0.025, -0.005, 0.005, -0.025, 0])
    ),
    'bezier': BezierRestToRest(
        BezierParams(start=(0.0, 0.01, -0.002), end=(0.01, 0.0, 0.003), t1=0.5, t2=2.0)
    ),
    'program': ProgramTrajectory(
        ProgramParams(
            start=(0.0, 0.0, 0.0),
            segments=[
                'linear 0.01 0 0 0.01',
                'bezier 0.01 -0.02 0.004 1.0',
                'dwell 0.2',
                'linear 0 0 0 0.02',
            ],
        )
    ),
    'sinusoid': Sinusoid(
        SinusoidParams(
            center=(0.1, -0.2, 0.0),
            amplitude=(0.01, -0.002, 0.0),
            frequency=(0.5, 1.0, 2.0),
            duration=2.0,
        )
    ),
}


@pytest.mark.parametrize('name', PATHS)
def test_the_box_is_the_box_of_the_samples(name: str) -> None:
    path: Trajectory = PATHS[name]
    lo, hi = (np.array(v) for v in path.bounds(STEP))
    sampled_lo, sampled_hi = (np.array(v) for v in Trajectory.bounds(path, STEP))
    assert np.all(lo <= sampled_lo + 1e-15) and np.all(hi >= sampled_hi - 1e-15)
    # a sampled box misses a peak by at most one step of motion
    assert np.allclose(lo, sampled_lo, atol=1e-6) and np.allclose(hi, sampled_hi, atol=1e-6)
