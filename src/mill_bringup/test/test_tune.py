"""`tune` on machine models made here: what it refuses with one line, its margins, the
parameter file, and a run's tracking set beside the prediction."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from mill_analysis.identify import machine_file
from mill_bringup.tuning.cli import main as tune
from mill_bringup.tuning.prediction_file import compare, prediction_path
from mill_models.identification import AxisIdentification, Interval

from mill_bringup import scenario


def axis(b: float = 16.0, beta: float = 0.5, gamma: float = 0.0, delay: int = 1):
    return AxisIdentification(
        0.001,
        delay,
        Interval(b, 0.01),
        Interval(0.08, 0.005),
        Interval(beta, 0.001),
        Interval(gamma, 0.001),
        resolution=1e-6,
        windows=100,
        rejected=0,
        held_out=30,
        fit_rms=2.9e-7,
        validation_rms=2.9e-7,
    )


def write(tmp_path: Path, **axes: AxisIdentification) -> Path:
    path = tmp_path / 'machine.yaml'
    machine_file.write(path, machine_file.MachineModel(0.001, dict(axes), 'made here'))
    return path


def refused(capsys, argv: list[str]) -> str:
    assert tune(argv) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith('tune: error: '), err
    return err[0]


def test_a_machine_file_round_trips(tmp_path) -> None:
    a = axis(gamma=2.5)
    path = write(tmp_path, x=a)
    assert machine_file.read(path).axes['x'] == a


@pytest.mark.parametrize(
    ('text', 'says'),
    [
        ('', 'not a machine model'),
        ('mill_machine_model: 1\nsample_period: 0.001\naxes: {q: {}}\n', "unknown axis 'q'"),
        ('mill_machine_model: 1\nsample_period: -1\naxes: {}\n', 'must be > 0'),
        ('mill_machine_model: 1\nsample_period: 0.001\naxes: {x: {delay: 1}}\n', 'missing b'),
        ('[', 'not valid YAML'),
    ],
)
def test_a_bad_machine_file_is_one_line(tmp_path, capsys, text: str, says: str) -> None:
    path = tmp_path / 'm.yaml'
    path.write_text(text)
    assert says in refused(capsys, [str(path)])


def test_a_missing_file_is_one_line(tmp_path, capsys) -> None:
    assert 'No such file' in refused(capsys, [str(tmp_path / 'nowhere.yaml')])


def test_friction_that_takes_the_torque_is_refused(tmp_path, capsys) -> None:
    path = write(tmp_path, x=axis(beta=30.0, gamma=20.0))  # (30 + 20)/16 = 3.1 N·m of 5
    assert 'nothing left to accelerate with' in refused(capsys, [str(path)])
    assert not (tmp_path / 'tuned.yaml').exists()


def test_another_rate_needs_the_drives_delay(tmp_path, capsys) -> None:
    path = write(tmp_path, x=axis())
    assert 'give --delay' in refused(capsys, [str(path), '--sample-period', '0.004'])


def test_axes_with_different_delays_need_one_delay(tmp_path, capsys) -> None:
    path = write(tmp_path, x=axis(delay=1), y=axis(delay=2))
    assert 'different delays' in refused(capsys, [str(path)])


def test_the_parameter_file_holds_the_design_and_the_run_is_set_beside_the_prediction(
    tmp_path, capsys
) -> None:
    path = write(tmp_path, x=axis(), y=axis(b=21.0), z=axis(b=17.0, gamma=2.7))
    out = tmp_path / 'tuned.yaml'
    argv = [str(path), '-o', str(out), '--scenario', 'commissioning']
    assert tune([*argv, '--min-following-error', '0.0002', '--max-velocity', '0.05']) == 0
    printed = capsys.readouterr().out
    assert 'phase margin' in printed and '30°' in printed
    assert (tmp_path / 'tuned.bode.png').stat().st_size > 10_000  # the loops' Bode plot
    params = yaml.safe_load(out.read_text())
    x = params['/**/x_controller']['ros__parameters']
    assert (x['following_error_limit'], x['min_following_error']) == (0.001, 0.0002)
    assert x['max_velocity'] == 0.05
    z = params['/**/z_observer']['ros__parameters']
    assert z['hold_torque'] == pytest.approx(2.7 / 17.0)
    assert z['eso.omega_o'] == pytest.approx(300.0)  # 0.75 / ((1 + 3/2) · 1 ms)
    assert params['/**/x_controller']['ros__parameters']['pd.omega_c'] == pytest.approx(100.0)
    pred = yaml.safe_load(prediction_path(out).read_text())
    scen = scenario.load('commissioning')
    scenario.apply_params_file(scen, str(out))
    skips = []

    def measured(skip: float) -> dict[str, float]:
        skips.append(skip)  # the prediction's window
        return {a: 3.0 * pred['rms_error'][a] for a in 'xyz'}

    (compared,) = compare(scen, pred['end'], measured)
    lines = compared.lines()
    assert '(3.00x)' in lines[0] and lines[1].startswith('WARNING: x, y, z tracked')
    assert skips == [pred['skip']]
    assert 'not compared' in compare(scen, pred['end'] / 2, measured)[0].lines()[0]


def test_an_observer_whose_loop_has_too_little_margin_is_refused(tmp_path, capsys) -> None:
    # Beltrán's degree-4 GPI observer at the rule's bandwidth: about 8° of phase margin
    path = write(tmp_path, x=axis())
    line = refused(capsys, [str(path), '--observer', 'gpi'])
    assert 'phase margin of' in line and 'below 20°' in line
    assert not (tmp_path / 'tuned.yaml').exists()
