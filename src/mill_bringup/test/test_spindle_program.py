"""M3/M4/M5 switch the plant's cutting force (spindle: reference), offline."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from mill_bringup.cli import set_program
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.registry import job_for
from mill_trajectory.config import build_job

from mill_bringup import scenario

# The slot's tool 5 mm deep in the work: 1 mm cut, 1 mm with the spindle off, 1 mm cut.
PART = """G21 G90 G17
S1800 M3
G1 Y-104 F180
M5
G1 Y-103
M4
G1 Y-102
M30
"""


def test_no_cutting_force_while_the_spindle_is_off(tmp_path: Path) -> None:
    part = tmp_path / 'part.ngc'
    part.write_text(PART)
    scen = scenario.load('slotting')
    set_program(scen, str(part))
    assert scen.parameters('plant')['spindle'] == 'reference'
    path = build_job(scen.parameters('trajectory')).trajectory
    rec = simulate(job_for(scen))
    spindle = np.array([path.sample(float(t)).spindle for t in rec.t])
    assert set(spindle) == {1800.0, 0.0, -1800.0}
    # The force of sample k + 1 comes from the step k -> k + 1, with the spindle of sample k.
    force = np.abs(rec['force'][1:]).max(axis=1)
    off = spindle[:-1] == 0.0
    assert off.sum() > 300 and force[off].max() == 0.0
    # Cutting: the two teeth's force, well above 0 over each revolution (1/30 s) where it runs.
    for sign in (1.0, -1.0):
        cut = force[np.sign(spindle[:-1]) == sign]
        revolutions = cut[: len(cut) // 33 * 33].reshape(-1, 33)
        assert revolutions.max(axis=1).min() > 100.0
    assert rec['force'][0].tolist() == [0.0, 0.0, 0.0]  # off before the reference says
