"""The gcode path type: the papers' slot as G-code, the travel, the feed override's headroom."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from mill_bringup.scenario import load
from mill_common.parameters import ParameterError, validate
from mill_trajectory.config import build_job, parameter_specs
from mill_trajectory.feed_override import TimeScaledPath

CONFIG = Path(__file__).resolve().parents[3] / 'config'
SLOT = str(CONFIG / 'slotting.ngc')


def _values(**given) -> dict:
    specs = dict(parameter_specs())
    values = {name: spec.default for name, spec in specs.items()}
    values.update(given)
    return {name: validate(specs[name], value, name) for name, value in values.items()}


def _gcode(**given) -> dict:
    start = [-0.075, -0.105, -0.005]
    return _values(trajectory='gcode', **{'gcode.file': SLOT, 'gcode.start': start, **given})


def test_slot_with_velocity_steps_is_the_yaml_program_sample_for_sample() -> None:
    yaml_path = build_job(load('slotting').parameters('trajectory')).trajectory
    steps = {'gcode.max_acceleration': [0.0] * 3, 'gcode.max_jerk': [0.0] * 3}
    path = build_job(_gcode(**steps)).trajectory
    assert path.end_time == yaml_path.end_time
    spindles = set()
    for k in range(int(yaml_path.end_time * 1000) + 200):
        sample = path.sample(k * 1e-3)
        assert replace(sample, spindle=None) == yaml_path.sample(k * 1e-3), k
        spindles.add((k * 1e-3 < path.end_time, sample.spindle))
    # S1800 M3 before the cut, M5 after it: the YAML path programs no spindle.
    assert spindles == {(True, 1800.0), (False, 0.0)}


def test_slot_with_machine_limits_is_smooth_and_close_to_the_paper() -> None:
    path = build_job(_gcode()).trajectory
    ts = np.arange(0.0, path.end_time + 0.1, 1e-3)
    a = np.array([path.sample(float(t)).acceleration for t in ts])
    v = np.array([path.sample(float(t)).velocity for t in ts])
    assert np.abs(a).max() <= 0.5 and np.abs(np.diff(v, axis=0)).max() < 0.5 * 1e-3 * (1 + 1e-9)
    assert np.linalg.norm(v, axis=1).max() == pytest.approx(0.003, rel=1e-12)
    assert 160 / 3 < path.end_time < 160 / 3 + 0.5  # a little longer than 53.3 s
    # The corner costs ~0.06 s of the 53.3 s at F: the summary's line rounds to 100 %.
    assert path.feed_summary == 'feed held: 100 % of F on lines'


def test_a_program_outside_the_travel_is_refused_naming_the_line(tmp_path: Path) -> None:
    with pytest.raises(ParameterError, match=r'slotting\.ngc:7:1: move outside the machine'):
        build_job(_gcode(**{'travel.max': [0.0, 0.0, 0.0]}))
    with pytest.raises(ValueError, match=r'leaves the machine travel: y = '):
        build_job(load('slotting').parameters('trajectory') | {'travel.min': [-1, -0.1, -1]})


def test_feed_override_up_to_its_max_keeps_the_limits() -> None:
    values = _gcode(**{'feed_override.enabled': True, 'feed_override.max': 2.0})
    path = build_job(values).trajectory
    scaled = TimeScaledPath(path, 1e-3)
    v, a = [], []
    while scaled.path_time < path.end_time:
        s = scaled.sample(2.0)
        v.append(s.velocity)
        a.append(s.acceleration)
    assert np.abs(np.array(a)).max() <= 0.5 * (1 + 1e-9)
    assert np.abs(np.array(v)).max() == pytest.approx(0.006, rel=1e-12)  # 2 x the feed
