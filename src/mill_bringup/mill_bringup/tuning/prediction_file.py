"""The prediction `tune` makes for a parameter file, and a run's tracking beside it.

It sits next to the parameter file as NAME.prediction.yaml (what the job should track on the
identified machine, run offline); a run given that parameter file (`--params-file`) prints its
own RMS tracking error beside the prediction (mill_analysis.summary.PredictionComparison), both
over the job's window after the approach a realtime job starts with, and a warning where it
is more than mill_analysis.summary.WORSE times.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml
from mill_analysis.summary import PredictionComparison
from mill_common.yaml_files import read_yaml

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
        data = read_yaml(prediction_path(params_file))
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return None
    if not isinstance(data, dict) or not isinstance(data.get('rms_error'), dict):
        return None
    ok = all(isinstance(v, float) and math.isfinite(v) for v in data['rms_error'].values())
    return data if ok else None


def compare(
    scen: Scenario, end: float, measured: Callable[[float], Mapping[str, float]]
) -> list[PredictionComparison]:
    """A run beside tune's prediction, for every parameter file of the run that has one
    (none: no comparison). end: the run's last sample after its approach [s] (the job's
    path alone, as the prediction ran it); measured(skip): the run's RMS e per axis over
    the job's window from `skip` s after its path started (the prediction's skip)."""
    out = []
    for path in scen.params_files:
        data = read_prediction(path)
        if data is None:
            continue
        if data.get('scenario') != scen.name:
            note = f'tune predicted {data.get("scenario")!r}, not {scen.name}: not compared'
            out.append(PredictionComparison(str(path), note=note))
            continue
        period = float(data.get('sample_period', 0.0))
        # a realtime record ends on the drive's tick, within a period of the job's end
        if not math.isclose(float(data.get('end', -1.0)), end, abs_tol=1.5 * period):
            note = (
                f'tune predicted {data["scenario"]} to t = {data.get("end")} s, this run ends at '
                f'{end:g} s: not compared'
            )
            out.append(PredictionComparison(str(path), note=note))
            continue
        rms = measured(float(data.get('skip', 0.0)))
        predicted = {a: float(v) for a, v in data['rms_error'].items() if v and a in rms}
        given = ' '.join(f'-p {o}' for o in data.get('overrides') or [])
        source = f'{path}, predicted with {given}' if given else str(path)
        kept = {a: rms[a] for a in rms if a in predicted}
        out.append(PredictionComparison(source, kept, predicted))
    return out
