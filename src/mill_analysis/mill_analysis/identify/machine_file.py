"""The identified machine as a YAML file: what `identify` writes and `tune` reads.

One entry per axis with the model of mill_models.identification (b, α, β, γ with their 95 %
half-widths, the delay in samples) and the sample period it was identified at. A file that
is not such a model is refused with one line (MachineFileError).

Each axis also says which model its record supports and why (mill_models.axis_model):
`model` (rigid, two_mass), `reason` (one line), and what was seen: `two_mass` (b, mass
ratio m2/m1, ω_r, ζ with half-widths, resonance and anti-resonance in Hz, delay [s]),
`stribeck` (Coulomb and static friction as accelerations, Stribeck speed [m/s]),
`backlash` (width [m]) and `frequency_band` (the band the response was fitted over [Hz])
and `excitation_band` (what the excitation covered [Hz]). `read` gives the rigid models and
refuses an axis whose chosen model is not rigid: `tune` designs for rigid axes only.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml
from mill_common.signals import AXES
from mill_models.axis_model import RIGID, AxisModel
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
        raw = yaml.safe_load(Path(path).read_text())
    except OSError as exc:
        raise MachineFileError(f'{where}: {exc.strerror or exc}') from None
    except yaml.YAMLError as exc:
        raise MachineFileError(f'{where}: not valid YAML ({str(exc).splitlines()[0]})') from None
    if not isinstance(raw, dict) or raw.get('mill_machine_model') != VERSION:
        raise MachineFileError(f'{where}: not a machine model written by identify')
    T = _number(raw.get('sample_period'), f'{where}: sample_period')
    if not T > 0.0:
        raise MachineFileError(f'{where}: sample_period must be > 0, got {T!r}')
    axes = raw.get('axes')
    if not isinstance(axes, dict) or not axes:
        raise MachineFileError(f'{where}: no axes')
    out = {}
    for axis, entry in axes.items():
        if axis not in AXES:
            raise MachineFileError(f'{where}: unknown axis {axis!r} (axes are x, y, z)')
        out[axis] = _axis(entry, T, f'{where}: axis {axis}')
    return MachineModel(T, out, str(raw.get('source', '')))


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise MachineFileError(f'{where} must be a finite number, got {value!r}')
    return float(value)


def _axis(entry: Any, T: float, where: str) -> AxisIdentification:
    if not isinstance(entry, Mapping):
        raise MachineFileError(f'{where}: not a mapping')
    chosen = entry.get('model', RIGID)
    if chosen != RIGID:
        raise MachineFileError(
            f'{where}: a {chosen} model ({entry.get("reason", "?")}): tune designs for rigid '
            f'axes only'
        )
    missing = [f for f in FIELDS if f not in entry]
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
