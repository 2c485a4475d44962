"""The identified machine as a YAML file: what `identify` writes and `tune` reads.

One entry per axis with the model of mill_models.identification (b, α, β, γ with their 95 %
half-widths, the delay in samples) and the sample period it was identified at. A file that
is not such a model is refused with one line (MachineFileError).

Each axis also says which model its record supports and why (mill_models.axis_model):
`model` (rigid, two_mass), `reason` (one line), and what was seen: `two_mass` (b, mass
ratio m2/m1, ω_r, ζ with half-widths, resonance and anti-resonance in Hz, delay [s]),
`stribeck` (Coulomb and static friction as accelerations, Stribeck speed [m/s]),
`backlash` (width [m]) and `frequency_band` (the band the response was fitted over [Hz])
and `excitation_band` (what the excitation covered [Hz]). The measured frequency response
itself (per axis the bins, X/U, coherence and the excitation's PSD) is written beside the
file as NAME.frf.npz, for `tune`'s margins on the measured response.

A two-mass axis carries the rigid model's fields too: its slow fit (mill_models.axis_model:
the rigid fit at the delay its response shows), the whole axis's gain, friction and load.
`read` gives the rigid (or slow) models, and in `structure` what was seen of each axis
(its model and reason, two-mass model, Stribeck friction, backlash, frequency response), and
refuses an axis that has no model (`none`) or a two-mass one without the slow fit.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from mill_common.signals import AXES
from mill_common.yaml_files import read_yaml, yaml_problem
from mill_models.axis_model import RIGID, TWO_MASS, AxisModel
from mill_models.backlash_id import Backlash
from mill_models.frequency_response import FrequencyResponse, FrfAnalysis, TwoMassModel
from mill_models.friction_id import StribeckFriction
from mill_models.identification import NAMES, AxisIdentification, Interval

VERSION = 1
FIELDS = (
    'delay',
    *NAMES,
    *(f'{n}_ci' for n in NAMES),
    'resolution',
    'fit_rms',
    'validation_rms',
    'windows',
    'rejected',
    'held_out',
)


class MachineFileError(ValueError):
    """str() is the one line that says what is wrong with the file."""


@dataclass(frozen=True)
class MachineModel:
    sample_period: float  # [s]
    axes: dict[str, AxisIdentification]
    source: str = ''  # the bag it was identified from
    structure: dict[str, AxisModel] = field(default_factory=dict)  # the model chosen, and why


def write(path: Path, model: MachineModel) -> None:
    data: dict[str, Any] = {
        'mill_machine_model': VERSION,
        'source': model.source,
        'sample_period': model.sample_period,
        'axes': {
            a: {
                **(_axis_dict(model.axes[a]) if a in model.axes else {}),
                **_structure(model.structure.get(a)),
            }
            for a in [*model.axes, *(a for a in model.structure if a not in model.axes)]
        },
    }
    header = (
        '# The identified model of each axis (identify; docs/bring-up.md):\n'
        "# x'' = b·u(t − delay·T) − alpha·x' − beta·sign(x') − gamma, with 95 % half-widths"
        ' (*_ci)\n'
    )
    path.write_text(header + yaml.safe_dump(data, sort_keys=False))
    responses = {a: m.response.response for a, m in model.structure.items() if m.response}
    if responses:
        _write_responses(response_path(path), responses)


def response_path(path: Path) -> Path:
    """Where the measured frequency responses of the machine file `path` are."""
    return Path(path).with_suffix('.frf.npz')


def _write_responses(path: Path, responses: Mapping[str, FrequencyResponse]) -> None:
    arrays: dict[str, Any] = {}
    for a, r in responses.items():
        arrays.update(
            {
                f'{a}_f': r.f,
                f'{a}_h': r.h,
                f'{a}_coherence': r.coherence,
                f'{a}_psd': r.excitation_psd,
                f'{a}_info': np.array([r.sample_period, r.segments]),
                f'{a}_source': np.array(r.source),
            }
        )
    with path.open('wb') as f:
        np.savez_compressed(f, **arrays)


def _read_responses(path: Path) -> dict[str, FrequencyResponse]:
    try:
        data = np.load(path)
    except (OSError, ValueError):
        return {}
    out = {}
    for a in AXES:
        if f'{a}_f' in data:
            T, segments = (float(v) for v in data[f'{a}_info'])
            out[a] = FrequencyResponse(
                data[f'{a}_f'],
                data[f'{a}_h'],
                data[f'{a}_coherence'],
                data[f'{a}_psd'],
                T,
                int(segments),
                str(data[f'{a}_source']),
            )
    return out


def _axis_dict(m: AxisIdentification) -> dict[str, float | int]:
    d = m.as_dict()
    d.pop('sample_period')
    return d


def _structure(m: AxisModel | None) -> dict[str, Any]:
    if m is None:
        return {}
    out: dict[str, Any] = {'model': m.model, 'reason': m.reason}
    if m.two_mass is not None:
        out['two_mass'] = m.two_mass.as_dict()
    if m.friction is not None:
        out['stribeck'] = m.friction.as_dict()
    if m.backlash is not None:
        out['backlash'] = m.backlash.as_dict()
    if m.response is not None and m.response.bins:
        out['frequency_band'] = list(m.response.band)
        out['excitation_band'] = list(m.response.excitation_band)
    return {k: _plain(v) for k, v in out.items()}


def _plain(value: Any) -> Any:
    """numpy scalars as Python numbers (safe_dump writes only those)."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value.item() if hasattr(value, 'item') else value


def read(path: Path) -> MachineModel:
    where = f'machine model {path}'
    try:
        raw = read_yaml(path)
    except OSError as exc:
        raise MachineFileError(f'{where}: {exc.strerror or exc}') from None
    except UnicodeDecodeError:
        raise MachineFileError(f'{where}: not a text file') from None
    except yaml.YAMLError as exc:
        raise MachineFileError(f'{where}: {yaml_problem(exc)}') from None
    if not isinstance(raw, dict) or raw.get('mill_machine_model') != VERSION:
        raise MachineFileError(f'{where}: not a machine model written by identify')
    T = _number(raw.get('sample_period'), f'{where}: sample_period')
    if not T > 0.0:
        raise MachineFileError(f'{where}: sample_period must be > 0, got {T!r}')
    axes = raw.get('axes')
    if not isinstance(axes, dict) or not axes:
        raise MachineFileError(f'{where}: no axes')
    out = {}
    responses = _read_responses(response_path(path))
    structure = {}
    for axis, entry in axes.items():
        if axis not in AXES:
            raise MachineFileError(f'{where}: unknown axis {axis!r} (axes are x, y, z)')
        out[axis] = _axis(entry, T, f'{where}: axis {axis}')
        structure[axis] = _axis_structure(entry, out[axis], responses.get(axis))
    return MachineModel(T, out, str(raw.get('source', '')), structure)


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise MachineFileError(f'{where} must be a finite number, got {value!r}')
    return float(value)


def _axis(entry: Any, T: float, where: str) -> AxisIdentification:
    if not isinstance(entry, Mapping):
        raise MachineFileError(f'{where}: not a mapping')
    chosen = entry.get('model', RIGID)
    if chosen not in (RIGID, TWO_MASS):
        raise MachineFileError(
            f'{where}: a {chosen} model ({entry.get("reason", "?")}): tune designs for rigid '
            f'and two-mass axes only'
        )
    missing = [f for f in FIELDS if f not in entry]
    if chosen == TWO_MASS and missing:
        raise MachineFileError(
            f'{where}: a two_mass model ({entry.get("reason", "?")}) without the rigid fit at '
            f'its delay (its gain, friction and load): tune cannot design for it'
        )
    if missing:
        raise MachineFileError(f'{where}: missing {", ".join(missing)}')
    v = {f: _number(entry[f], f'{where}: {f}') for f in FIELDS}
    if v['delay'] != int(v['delay']) or v['delay'] < 0:
        raise MachineFileError(f'{where}: delay must be a whole number >= 0, got {v["delay"]!r}')
    return AxisIdentification(
        T,
        int(v['delay']),
        Interval(v['b'], v['b_ci']),
        Interval(v['alpha'], v['alpha_ci']),
        Interval(v['beta'], v['beta_ci']),
        Interval(v['gamma'], v['gamma_ci']),
        resolution=v['resolution'],
        windows=int(v['windows']),
        rejected=int(v['rejected']),
        held_out=int(v['held_out']),
        fit_rms=v['fit_rms'],
        validation_rms=v['validation_rms'],
    )


def _iv(d: Mapping[str, Any], name: str) -> Interval:
    return Interval(float(d[name]), float(d.get(f'{name}_ci', 0.0)))


def _axis_structure(
    entry: Mapping[str, Any], fit: AxisIdentification, response: FrequencyResponse | None
) -> AxisModel:
    """What identify saw of the axis, as the AxisModel it chose (the fits' statistics that
    the file does not keep are NaN)."""
    where = 'machine model'
    try:
        two_mass = None
        if isinstance(entry.get('two_mass'), Mapping):
            d = entry['two_mass']
            two_mass = TwoMassModel(
                _iv(d, 'b'),
                _iv(d, 'mass_ratio'),
                _iv(d, 'omega_r'),
                _iv(d, 'zeta'),
                float(d['delay']),
                float(d['friction_damping']),
                math.nan,
            )
        friction = None
        if isinstance(entry.get('stribeck'), Mapping):
            d = entry['stribeck']
            friction = StribeckFriction(
                _iv(d, 'coulomb'),
                _iv(d, 'static'),
                _iv(d, 'stribeck_speed') if 'stribeck_speed' in d else None,
                fit.alpha,
                int(d.get('stops', 0)),
                bool(d.get('present', False)),
                str(d.get('reason', '')),
            )
        backlash = None
        if isinstance(entry.get('backlash'), Mapping):
            d = entry['backlash']
            backlash = Backlash(
                _iv(d, 'width'),
                int(d.get('reversals', 0)),
                bool(d.get('present', False)),
                str(d.get('reason', '')),
                source=str(d.get('source', 'table')),
            )
    except (KeyError, TypeError, ValueError) as exc:
        raise MachineFileError(f'{where}: a malformed structure entry ({exc})') from None
    band = entry.get('frequency_band') or [math.nan, math.nan]
    analysis = None
    if response is not None or two_mass is not None:
        empty = np.zeros(0)
        analysis = FrfAnalysis(
            response or FrequencyResponse(empty, empty, empty, empty, fit.sample_period, 0, ''),
            (float(band[0]), float(band[1])),
            int(response.f.size) if response is not None else 0,
            fit.b.value,
            fit.delay * fit.sample_period,
            math.nan,
            two_mass,
            two_mass,
            str(entry.get('reason', '')),
            tuple(entry.get('excitation_band') or (math.nan, math.nan)),
        )
    model = str(entry.get('model', RIGID))
    rigid, slow = (fit, None) if model == RIGID else (None, fit)
    return AxisModel(
        model,
        str(entry.get('reason', '')),
        rigid,
        '',
        analysis,
        friction,
        backlash,
        slow,
    )
