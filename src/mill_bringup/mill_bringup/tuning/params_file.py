"""The ROS 2 parameter file `tune` writes, and the prediction that goes with it.

The parameter file holds only what tune designed: the sample period, and per axis the
controller's and the observer's law, gains, input gain, delay and load; a scenario or a
launch takes it with `--params-file` / `params_file:=`. Its prediction (what the job should
track on the identified machine) sits next to it as NAME.prediction.yaml, which the runner
reads to put a run's tracking beside it.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import yaml

from mill_bringup.scenario import dump_parameters
from mill_bringup.tuning.predict import Prediction


def prediction_path(params_file: str | Path) -> Path:
    p = Path(params_file)
    return p.with_name(p.stem + '.prediction.yaml')


def write_params(path: Path, T: float, nodes: dict[str, dict[str, Any]], header: str) -> None:
    data: dict[str, Any] = {'/**': {'ros__parameters': {'sample_period': T, 'design_period': 0.0}}}
    for node, values in nodes.items():
        data[f'/**/{node}'] = {'ros__parameters': values}
    lines = ''.join(f'# {line}\n' if line else '#\n' for line in header.splitlines())
    path.write_text(lines + dump_parameters(data))


def write_prediction(path: Path, p: Prediction) -> None:
    data = {
        'scenario': p.scenario,
        'sample_period': p.sample_period,
        'skip': p.skip,
        'rms_error': p.rms,
        'max_error': p.max,
        'events': p.events,
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
