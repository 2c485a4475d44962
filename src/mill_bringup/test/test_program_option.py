"""--program: a scenario runs a G-code part (the adaptive-feed job on adaptive_feed_part.ngc)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from mill_bringup.cli import set_program
from mill_bringup.jobs.axis import depth_stretches
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.registry import job_for
from mill_bringup.scenario import ScenarioError

from mill_bringup import scenario

CONFIG = Path(__file__).resolve().parents[3] / 'config'


def test_adaptive_feed_job_on_a_gcode_part() -> None:
    scen = scenario.load('slotting_adaptive_feed')
    set_program(scen, str(CONFIG / 'adaptive_feed_part.ngc'))
    params = scen.parameters('trajectory')
    assert params['trajectory'] == 'gcode'
    assert params['gcode.start'] == [-0.075, -0.105, -0.005]
    job = job_for(scen)
    rec = simulate(job)
    # the summary says how much of the programmed feed the plan holds (lines only here)
    (held,) = [line for line in job.summary(rec, 1.0).text().splitlines() if 'feed held' in line]
    assert held.startswith('feed held: ') and held.endswith(' % of F on lines')
    deep, shallow = depth_stretches(rec.force_control)
    assert (deep.depth, shallow.depth) == (5.0, 2.0)
    # the law slows the feed in the deep cut and speeds it up in the shallow one
    assert deep.override < 1.0 < shallow.override
    assert abs(deep.force - 300.0) < 5.0
    # the path ends where the part ends, reached by the planned (override-scaled) reference
    assert rec['reference'][-1] == pytest.approx([-0.075, -0.076, -0.002], abs=1e-12)
    # planned for override up to 2: the reference speed stays within 2 x the planned one
    assert np.abs(rec['reference_velocity']).max() <= 0.05 * (1 + 1e-9)


@pytest.mark.parametrize(
    ('text', 'message'),
    [
        ('G1 Y-25 F180\nG1 X5 Y0 R0.001\n', r'part\.ngc:2:10: word R'),
        ('G1 Y-25 F0\n', r'part\.ngc:1:9: feed F0 must be > 0'),
    ],
)
def test_a_bad_program_is_refused_before_anything_starts(tmp_path, text, message) -> None:
    part = tmp_path / 'part.ngc'
    part.write_text(text)
    with pytest.raises(ScenarioError, match=message):
        set_program(scenario.load('slotting'), str(part))
    with pytest.raises(ScenarioError, match='no such G-code file'):
        set_program(scenario.load('slotting'), str(tmp_path / 'none.ngc'))
