"""`tune MACHINE`: the parameter file for an identified machine, its margins and prediction.

Reads the machine model `identify` wrote, designs every axis's ADRC law and ESO observer at
the sample period asked for (mill_bringup.tuning.design), prints the margins of each loop as
built (mill_bringup.tuning.margins), writes the ROS 2 parameter file and runs the job offline
on the identified machine for the tracking it predicts (mill_bringup.tuning.predict), which a
`run_scenario SCENARIO --params-file FILE` run then reports itself against. Anything that
cannot be tuned gets one line and no file (exit 1); bad options one line (exit 2).
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import replace
from functools import partial
from pathlib import Path

from mill_analysis.identify.machine_file import MachineFileError, MachineModel, read
from mill_common.one_line_parser import OneLineParser, positive
from mill_controllers.config import build_loop
from mill_models.axis_model import TWO_MASS, AxisModel
from mill_models.frequency_response import measured_to
from mill_models.identification import AxisIdentification
from mill_observers.config import build_observer_loop

from mill_bringup.job_config import JobConfig, build
from mill_bringup.scenario import ScenarioError, load
from mill_bringup.tuning.bode import bode_path, plot_bode
from mill_bringup.tuning.design import (
    MIN_GAIN_MARGIN,
    MIN_MEASURED_PHASE,
    MIN_PHASE_MARGIN,
    NOTCH_DAMPINGS,
    AxisTuning,
    TuneError,
    backlash_values,
    choose_for_resonance,
    controller_values,
    design_axis,
    friction_values,
    notch_values,
    observer_values,
)
from mill_bringup.tuning.margins import Margins, UnstableLoop, margins
from mill_bringup.tuning.params_file import write_params
from mill_bringup.tuning.plant_response import PlantResponse, lightly_damped, plant_response
from mill_bringup.tuning.predict import predict
from mill_bringup.tuning.prediction_file import Prediction, prediction_path, write_prediction


def _parser() -> OneLineParser:
    p = OneLineParser(
        prog='tune',
        description='Design the ADRC law and ESO observer of every identified axis for a sample '
        'period (pole placement at the bandwidths of the tuning rule, limited by the encoder), '
        'print their margins, write the ROS 2 parameter file and predict the tracking of a job '
        'on the identified machine.',
    )
    p.add_argument('machine', help='machine model written by identify')
    p.add_argument('--sample-period', type=positive, help='[s] (default: as identified)')
    p.add_argument(
        '--delay',
        type=int,
        help='command delay [samples] (default: as identified; needed at another sample period)',
    )
    p.add_argument(
        '--observer',
        choices=('eso', 'gpi'),
        default='eso',
        help='eso (degree 0, the default) or gpi (Beltrán eq. (13)-(18), degree 4) at the '
        "rule's bandwidth",
    )
    p.add_argument(
        '--min-phase-margin',
        type=float,
        default=MIN_PHASE_MARGIN,
        help='refuse a design whose loop has less [deg] (default %(default)g)',
    )
    p.add_argument('--torque-limit', type=positive, default=5.0, help='[N·m] (default 5)')
    p.add_argument(
        '--following-error-limit',
        type=positive,
        default=0.001,
        help='trip threshold [m] (default 0.001)',
    )
    p.add_argument(
        '--min-following-error',
        type=float,
        default=0.0,
        help='the trip threshold at rest [m], growing with the reference speed to '
        '--following-error-limit at --max-velocity (LinuxCNC MIN_FERROR; default 0: the '
        'limit is fixed)',
    )
    p.add_argument(
        '--max-velocity',
        type=positive,
        default=0.1,
        help='the speed at which the trip threshold reaches --following-error-limit [m/s] '
        '(default 0.1)',
    )
    p.add_argument(
        '--scenario',
        default='slotting',
        help='the job to predict (default slotting); its nodes are named '
        '<axis>_controller and <axis>_observer',
    )
    p.add_argument(
        '--param',
        '-p',
        action='append',
        default=[],
        metavar='NODE.NAME=VALUE',
        help='override a parameter of the scenario predicted (as run_scenario -p), e.g. '
        'plant.cutting_model=none for a job in the air; give the run the same',
    )
    p.add_argument('--duration', type=positive, help='predict only this much of the job [s]')
    p.add_argument('--skip', type=float, default=1.0, help='metrics over t >= SKIP [s]')
    p.add_argument(
        '--output',
        '-o',
        type=Path,
        help='parameter file (default: tuned.yaml next to the machine model)',
    )
    return p


def tuning_config(scenario: str, T: float, delay: int) -> JobConfig:
    """The scenario's job configuration at the tuned rate and delay, built and checked once
    (ScenarioError, one line, if it cannot run there)."""
    scen = load(scenario)
    for text in (f'*.sample_period={T!r}', '*.design_period=0.0', f'*.command_delay={delay}'):
        scen.add_override(text)
    return build(scen)


def _margins_at(
    config: JobConfig,
    axis: str,
    T: float,
    delay: int,
    m: AxisIdentification,
    observer: str,
    response: PlantResponse | None,
    worst_case: PlantResponse | None,
    shaping: dict[str, object],
    omega_o: float,
    omega_c: float,
) -> Margins:
    """The margins of the loop the nodes would build with these bandwidths, on the rigid
    model and on the axis's response: the axis's controller and observer values of the
    configuration with the tuned law, gains and command shaping."""
    cv = {
        **config.values(f'{axis}_controller'),
        'controller': 'adrc',
        'input_gain': m.b.value,
        **controller_values(omega_c),
        **shaping,
    }
    ov = {
        **config.values(f'{axis}_observer'),
        'observer': observer,
        'input_gain': m.b.value,
        **observer_values(observer, omega_o),
    }
    return margins(
        lambda: (build_observer_loop(ov), build_loop(cv)),
        m.b.value,
        m.alpha.value,
        delay,
        T,
        response,
        worst_case,
    )


def measured_band(structure: AxisModel | None) -> float | None:
    """Up to where identify measured the axis's response coherently [Hz] (None: nowhere,
    or no response was recorded)."""
    frf = structure.response if structure is not None else None
    return measured_to(frf.response) if frf is not None and frf.response.f.size else None


def _delay(model: MachineModel, T: float, asked: int | None) -> int:
    if asked is not None:
        if asked < 0:
            raise TuneError(f'--delay must be a whole number >= 0, got {asked}')
        return asked
    delays = {m.delay for m in model.axes.values()}
    if not math.isclose(T, model.sample_period, rel_tol=1e-9):
        raise TuneError(
            f'the machine was identified at T = {1e3 * model.sample_period:g} ms: at '
            f'{1e3 * T:g} ms give --delay (a drive that applies each command at its next tick: 1)'
        )
    if len(delays) != 1:
        raise TuneError(f'the axes have different delays {sorted(delays)}: give --delay')
    return delays.pop()


def _header(
    model: MachineModel, machine: str, T: float, delay: int, tuned: dict[str, AxisTuning]
) -> str:
    lines = [
        f'tune {machine}: ADRC law + ESO observer at T = {1e3 * T:g} ms, {delay} sample(s) '
        'of delay',
        f'identified from {model.source or "?"}',
    ]
    for a, t in tuned.items():
        lines.append(
            f'{a}: observer {t.omega_o:.1f} rad/s, controller {t.omega_c:.1f} rad/s '
            f'(limited by the {t.limited_by}); {t.margins.text()}'
        )
        lines.extend(f'{a}: {line}' for line in (*_why(t), *t.notes))
        if t.band_note:
            lines.append(f'{a}: {t.band_note}')
    return '\n'.join(lines)


def _why(t: AxisTuning) -> list[str]:
    """What the measured response says of the loop, and why the bandwidths came down."""
    mg = t.margins.measured
    if mg is None:
        return []
    lines = [
        f'on the measured response ({100 * mg.share:.0f} % of the bins measured, the fitted '
        f'model elsewhere; a two-mass model also with half its damping, the worse): '
        f'{mg.text()}'
    ]
    if t.at_rule is not None:
        state = '' if t.at_rule.stable else ', unstable on the fitted model'
        lines.append(
            f"at the rule's bandwidths it had {t.at_rule.text()}{state}: lowered until the "
            f'gain margin is {MIN_GAIN_MARGIN:g} dB and the phase margin {MIN_MEASURED_PHASE:g}°'
        )
    return lines


def _report(tuned: dict[str, AxisTuning], pred: Prediction | None) -> str:
    rows = [
        '| axis | ω_o [rad/s] | ω_c [rad/s] | limited by | crossover [rad/s] | phase margin | '
        'gain margin | delay margin [samples] | measured: phase / gain margin | encoder '
        'noise [mN·m RMS] | predicted RMS e [µm] | predicted max e [µm] |',
        '|---|---|---|---|---|---|---|---|---|---|---|---|',
    ]
    for a, t in tuned.items():
        mg = t.margins
        gm = 'inf' if math.isinf(mg.gain_db) else f'{mg.gain_db:.1f} dB'
        rms = f'{1e6 * pred.rms[a]:.3g}' if pred and a in pred.rms else '-'
        peak = f'{1e6 * pred.max[a]:.3g}' if pred and a in pred.max else '-'
        on = mg.measured
        measured = f'{on.phase:.0f}° / {on.gain_db:.1f} dB' if on is not None else '-'
        rows.append(
            f'| {a} | {t.omega_o:.1f} | {t.omega_c:.1f} | {t.limited_by} | {mg.crossover:.0f} | '
            f'{mg.phase:.0f}° | {gm} | {mg.delay:.2f} | {measured} | '
            f'{1e3 * t.torque_noise:.3g} | {rms} | {peak} |'
        )
    return '\n'.join(rows)


def _design(
    args: argparse.Namespace,
    config: JobConfig,
    a: str,
    m: AxisIdentification,
    structure: AxisModel | None,
    T: float,
    delay: int,
    response: PlantResponse | None,
    light: PlantResponse | None,
) -> AxisTuning:
    """The axis's design: for a two-mass axis the better of a notch at its resonance and a
    lowered bandwidth; a Stribeck friction's feed-forward in either (it feeds the reference's
    speed forward: the loop's margins do not depend on it)."""
    band = measured_band(structure)

    def design(shaping: dict[str, object]) -> AxisTuning:
        at = partial(_margins_at, config, a, T, delay, m, args.observer, response, light, shaping)
        found = design_axis(
            a,
            m,
            T,
            delay,
            args.torque_limit,
            at,
            args.observer,
            args.min_phase_margin,
            two_mass=structure is not None and structure.model == TWO_MASS,
            measured_to=band,
        )
        friction = friction_values(structure, m, found.omega_o)
        notes = found.notes
        if friction:
            notes = (
                *notes,
                'friction feed-forward from the identified Stribeck curve: breakaway '
                f'{friction["friction_compensation.breakaway"]:.3g} N·m, sliding '
                f'{friction["friction_compensation.sliding"]:.3g} N·m, Stribeck speed '
                f'{1e3 * float(friction["friction_compensation.stribeck_speed"]):.2g} mm/s, '  # type: ignore[arg-type]
                f'handed over to the observer at {found.omega_o:.0f} rad/s',
            )
        backlash, note = backlash_values(structure)
        notes = (*notes, note) if note else notes
        return replace(found, shaping={**shaping, **friction, **backlash}, notes=notes)

    lowered = design({})
    if structure is None or structure.model != TWO_MASS or structure.two_mass is None:
        return lowered
    notched: AxisTuning | None = None
    for zeta in NOTCH_DAMPINGS:
        try:
            found = design(notch_values(structure, zeta))
        except TuneError:
            continue
        if notched is None or found.omega_c > notched.omega_c:
            notched = found
    return choose_for_resonance(lowered, notched, structure)


def _tune_at(
    args: argparse.Namespace, model: MachineModel, T: float, delay: int
) -> dict[str, AxisTuning]:
    config = tuning_config(args.scenario, T, delay)
    tuned = {}
    for a, m in model.axes.items():
        structure = model.structure.get(a)
        response = plant_response(structure, m, T, delay)
        light = lightly_damped(structure, m, T, delay)
        tuned[a] = _design(args, config, a, m, structure, T, delay, response, light)
    return tuned


def _write(
    args: argparse.Namespace,
    model: MachineModel,
    out: Path,
    T: float,
    delay: int,
    tuned: dict[str, AxisTuning],
) -> None:
    nodes: dict[str, dict[str, object]] = {}
    for a, t in tuned.items():
        m = model.axes[a]
        nodes[f'{a}_controller'] = {
            **t.controller(m, delay, args.torque_limit, args.following_error_limit),
            'min_following_error': min(args.min_following_error, args.following_error_limit),
            'max_velocity': args.max_velocity,
        }
        nodes[f'{a}_observer'] = t.observer(m, delay)
    write_params(out, T, nodes, _header(model, args.machine, T, delay, tuned))


FASTER = (2, 4, 8)  # a job that cannot be held is tried at these multiples of the rate
FASTEST = 0.00025  # [s]: not beyond 4 kHz


def _held_at(args: argparse.Namespace, model: MachineModel, T: float, delay: int, out: Path) -> str:
    """Where a faster rate holds the job (the drive's delay the same number of its ticks):
    the text naming it, or '' when none up to FASTEST does."""
    trial = out.with_name(out.stem + '.faster.yaml')
    try:
        for k in FASTER:
            T2 = T / k
            if T2 < FASTEST * (1.0 - 1e-9):
                break
            try:
                _write(args, model, trial, T2, delay, _tune_at(args, model, T2, delay))
                pred = predict(
                    args.scenario, str(trial), model, delay, args.skip, args.duration, args.param
                )
            except (TuneError, ScenarioError, UnstableLoop):
                continue
            if not pred.events:
                rms = ', '.join(f'{a} {1e6 * v:.3g}' for a, v in pred.rms.items())
                return (
                    f'at {1.0 / T2:g} Hz ({delay} sample(s) of delay) it is held, predicted RMS '
                    f'e [µm] {rms}: tune {args.machine} --sample-period {T2:g} --delay {delay}'
                )
        return f'nor at any rate up to {1.0 / FASTEST:g} Hz'
    finally:
        trial.unlink(missing_ok=True)


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        model = read(Path(args.machine))
        T = args.sample_period or model.sample_period
        delay = _delay(model, T, args.delay)
        tuned = _tune_at(args, model, T, delay)
    except (MachineFileError, TuneError, ScenarioError) as exc:
        print(f'tune: error: {exc}', file=sys.stderr)
        return 1
    except UnstableLoop as exc:
        print(
            f'tune: error: {exc}: the identified model is not one this rule can stabilise',
            file=sys.stderr,
        )
        return 1
    out = args.output or Path(args.machine).resolve().parent / 'tuned.yaml'
    _write(args, model, out, T, delay, tuned)
    print(
        f'tune {args.machine}: T = {1e3 * T:g} ms, delay {delay} sample(s); predicting '
        f'{args.scenario} offline on the identified machine ...',
        flush=True,
    )
    try:
        pred = predict(args.scenario, str(out), model, delay, args.skip, args.duration, args.param)
    except (TuneError, ScenarioError) as exc:
        out.unlink()
        print(f'tune: error: {exc}', file=sys.stderr)
        return 1
    if pred.events:
        # refused before anything moves: no parameter file, one line saying why and where
        out.unlink()
        prediction_path(out).unlink(missing_ok=True)
        print(
            f'tune: error: {args.scenario} cannot be held at {1.0 / T:g} Hz: '
            f'{"; ".join(pred.events)}; {_held_at(args, model, T, delay, out)}',
            file=sys.stderr,
        )
        return 1
    write_prediction(prediction_path(out), pred)
    picture = bode_path(out)
    plot_bode(picture, tuned, T)
    print(_report(tuned, pred))
    for a, t in tuned.items():
        if t.band_note:
            print(f'{a}: {t.band_note}')
    print(
        f'parameter file: {out}\nprediction: {prediction_path(out)}\nBode plot: {picture}\n'
        f'next: run_scenario {args.scenario} --params-file {out}'
    )
    return 0


if __name__ == '__main__':
    sys.exit(main())
