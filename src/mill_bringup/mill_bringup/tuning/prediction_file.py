"""The prediction `tune` makes for a parameter file, and a run's tracking beside it.

It sits next to the parameter file as NAME.prediction.yaml (what the job should track on the
identified machine, run offline); a run given that parameter file (`--params-file`) prints its
own RMS tracking error beside the prediction, and a warning where it is more than WORSE times.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml
from mill_analysis.metrics import AxisMetrics

from mill_bringup.scenario import Scenario


@dataclass(frozen=True)
class Prediction:
    scenario: str
    sample_period: float
    skip: float
    end: float  # the job's last sample [s]
    rms: dict[str, float]  # [m]
    max: dict[str, float]  # [m]
    events: list[str]
    overrides: list[str]  # -p given to the prediction (a run should be given the same)


def prediction_path(params_file: str | Path) -> Path:
    p = Path(params_file)
    return p.with_name(p.stem + '.prediction.yaml')


def write_prediction(path: Path, p: Prediction) -> None:
    data = {
        'scenario': p.scenario,
        'sample_period': p.sample_period,
        'skip': p.skip,
        'end': p.end,
        'rms_error': p.rms,
        'max_error': p.max,
        'events': p.events,
        'overrides': p.overrides,
    }
    path.write_text(
        '# What `tune` predicts this job tracks on the identified machine (offline run).\n'
        + yaml.safe_dump(data, sort_keys=False)
    )


def read_prediction(params_file: str | Path) -> dict[str, Any] | None:
    """The prediction next to a parameter file, None if there is none or it is unreadable."""
    try:
        data = yaml.safe_load(prediction_path(params_file).read_text())
    except (OSError, yaml.YAMLError):
        return None
    if not isinstance(data, dict) or not isinstance(data.get('rms_error'), dict):
        return None
    ok = all(isinstance(v, float) and math.isfinite(v) for v in data['rms_error'].values())
    return data if ok else None


WORSE = 2.0  # a run this many times the predicted RMS error is reported as a warning


def against_prediction(scen: Scenario, metrics: list[AxisMetrics], end: float) -> list[str]:
    """Lines putting a run's RMS tracking error beside tune's prediction, for every
    parameter file of the run that has one (none: no lines)."""
    lines = []
    for path in scen.params_files:
        data = read_prediction(path)
        if data is None:
            continue
        if data.get('scenario') != scen.name:
            lines.append(f'tune predicted {data.get("scenario")!r}, not {scen.name}: not compared')
            continue
        period = float(data.get('sample_period', 0.0))
        # a realtime record ends on the drive's tick, within a period of the job's end
        if not math.isclose(float(data.get('end', -1.0)), end, abs_tol=1.5 * period):
            lines.append(
                f'tune predicted {data["scenario"]} to t = {data.get("end")} s, this run ends at '
                f'{end:g} s: not compared'
            )
            continue
        cells, worse = [], []
        for m in metrics:
            predicted = data['rms_error'].get(m.axis)
            if not predicted:
                continue
            ratio = m.rms_error / predicted
            cells.append(f'{m.axis} {1e6 * m.rms_error:.3g} / {1e6 * predicted:.3g} ({ratio:.2f}x)')
            if not ratio <= WORSE:
                worse.append(m.axis)
        given = ' '.join(f'-p {o}' for o in data.get('overrides') or [])
        source = f'{path}, predicted with {given}' if given else path
        lines.append(f'RMS e [µm] measured / predicted by tune ({source}): ' + ', '.join(cells))
        if worse:
            lines.append(
                f'WARNING: {", ".join(worse)} tracked more than {WORSE:g}x worse than predicted: '
                'the machine is not the one identified (re-identify: docs/bring-up.md)'
            )
    return lines
