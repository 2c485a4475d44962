"""`identify` says which model each axis got and why, and writes it where `tune` reads.

A record of two simulated axes (mill_models/test/ident_machines.py): x rigid like Beltrán's,
y two-mass (70 Hz, measured on the motor). The command line runs on it (the bag reader
replaced by the record), and the machine file it writes is read back as `tune` reads it.
"""

from __future__ import annotations

import importlib.util
import re
import sys
from functools import cache
from pathlib import Path
from types import ModuleType, SimpleNamespace

import numpy as np
import pytest
import yaml
from mill_analysis.identify import cli, machine_file
from mill_analysis.identify.fit_axes import structure_record
from mill_analysis.identify.table import structure_table
from mill_analysis.record import RunRecord
from mill_models.axis_model import RIGID, TWO_MASS, StructureSettings


def _machines() -> ModuleType:
    """mill_models's test support (its simulated machines), from the source tree: a test
    file, not a module of an installed package, so it is loaded by path."""
    path = Path(__file__).resolve().parents[2] / 'mill_models' / 'test' / 'ident_machines.py'
    spec = importlib.util.spec_from_file_location('ident_machines', path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules['ident_machines'] = module  # its dataclasses look themselves up there
    spec.loader.exec_module(module)
    return module


im = _machines()

T = 0.001


@cache
def two_axis_record() -> RunRecord:
    seconds = 21.0
    rec = RunRecord.empty(round(seconds / T), T)
    for i, machine in ((0, im.BELTRAN_X), (1, im.M2_Y)):
        r = im.run(machine, seconds=seconds, seed=i + 1)
        rec.signals['position'][:, i] = r.x
        rec.signals['torque'][:, i] = r.u
    return rec


def test_each_axis_gets_its_model_and_the_reason_in_the_table() -> None:
    found = structure_record(two_axis_record(), T, ['x', 'y'], 1.0, StructureSettings())
    x, y = found['x'][0], found['y'][0]
    assert x.model == RIGID and y.model == TWO_MASS
    assert y.two_mass is not None
    assert y.two_mass.resonance_hz == pytest.approx(70.0, rel=0.05)
    text = structure_table({'x': x, 'y': y}, pitch=im.PITCH)
    rows = {line.split('|')[1].strip(): line for line in text.splitlines() if line.startswith('| ')}
    assert '| rigid | none |' in rows['x'] and 'no Stribeck effect' in rows['x']
    assert '| two_mass | ' in rows['y']
    hz = float(re.search(r'\| two_mass \| ([\d.]+) ±', rows['y']).group(1))  # type: ignore[union-attr]
    assert hz == pytest.approx(70.0, rel=0.05)
    # x's friction as forces, with the pitch: breakaway = sliding = 20 N
    assert re.search(r'\| 20(\.\d+)? ± [\d.]+ / 20(\.\d+)? ± [\d.]+ \|', rows['x']), rows['x']
    assert text.splitlines()[-2:] == [x.line('x'), y.line('y')]
    assert y.line('y').startswith('y: two-mass model: a resonance at ')


def test_the_command_line_writes_both_models_and_tune_reads_the_two_mass_axis(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    run = SimpleNamespace(record=two_axis_record(), dt_ns=1_000_000)
    monkeypatch.setattr(cli, 'read_run', lambda bag: run)
    out = tmp_path / 'machine.yaml'
    code = cli.main(
        [
            str(tmp_path / 'bag'),
            '--axes',
            'x,y',
            '-o',
            str(out),
            '--plot',
            str(tmp_path / 'p.png'),
            '--pitch',
            str(im.PITCH),
        ]
    )
    printed = capsys.readouterr().out
    assert code == 0
    assert 'next: tune ' in printed
    data = yaml.safe_load(out.read_text())['axes']
    assert data['x']['model'] == RIGID and data['x']['stribeck']['present'] is False
    assert data['x']['backlash']['present'] is False
    assert data['x']['b'] == pytest.approx(im.BELTRAN_X.input_gain, rel=0.02)
    assert data['y']['model'] == TWO_MASS
    assert data['y']['two_mass']['resonance_hz'] == pytest.approx(70.0, rel=0.05)
    assert data['y']['reason'].startswith('two-mass model: a resonance at ')
    lo, hi = data['y']['excitation_band']
    # the job's short bits carry the excitation past 250 Hz (10 ms bits alone: below 100 Hz)
    assert lo < 1.0 and hi > 250.0
    # the slow fit (the rigid one at the response's delay) has the whole axis's gain and
    # friction: M2's y has 30 N of Coulomb friction on 70.9 kg
    assert data['y']['delay'] == 1
    assert data['y']['b'] == pytest.approx(im.M2_Y.input_gain, rel=0.02)
    assert data['y']['beta'] == pytest.approx(im.M2_Y.coulomb / im.M2_Y.mass, rel=0.05)
    back = machine_file.read(out)
    y = back.structure['y']
    assert y.model == TWO_MASS and y.two_mass is not None and y.response is not None
    assert y.two_mass.resonance_hz == pytest.approx(data['y']['two_mass']['resonance_hz'])
    # the measured response beside the file, bin for bin
    assert machine_file.response_path(out).exists()
    assert y.response.response.h.shape == y.response.response.coherence.shape
    assert y.response.response.f[-1] == pytest.approx(500.0)
    assert back.axes['y'].b.value == pytest.approx(data['y']['b'])
    # a two-mass axis without the slow fit is refused, saying why
    del data['y']['b']
    raw = yaml.safe_load(out.read_text())
    del raw['axes']['y']['b']
    out.write_text(yaml.safe_dump(raw))
    with pytest.raises(machine_file.MachineFileError, match=r'axis y: a two_mass model .*'):
        machine_file.read(out)


def test_a_rigid_axis_with_its_structure_reads_back_as_tune_reads_it(tmp_path: Path) -> None:
    found = structure_record(two_axis_record(), T, ['x'], 1.0, StructureSettings())
    m = found['x'][0]
    assert m.rigid is not None
    path = tmp_path / 'm.yaml'
    machine_file.write(path, machine_file.MachineModel(T, {'x': m.rigid}, 'bag', {'x': m}))
    back = machine_file.read(path)
    assert back.axes['x'].b == m.rigid.b and back.axes['x'].delay == m.rigid.delay
    entry = yaml.safe_load(path.read_text())['axes']['x']
    assert entry['reason'] == m.reason
    assert np.isclose(entry['frequency_band'][0], 10.0, atol=0.5)
