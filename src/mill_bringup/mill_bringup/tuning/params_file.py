"""The ROS 2 parameter file `tune` writes: only what tune designed.

The sample period, and per axis the controller's and the observer's law, gains, input gain,
delay and load; a scenario or a launch takes it with `--params-file` / `params_file:=`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from mill_bringup.scenario import dump_parameters


def write_params(path: Path, T: float, nodes: dict[str, dict[str, Any]], header: str) -> None:
    data: dict[str, Any] = {'/**': {'ros__parameters': {'sample_period': T, 'design_period': 0.0}}}
    for node, values in nodes.items():
        data[f'/**/{node}'] = {'ros__parameters': values}
    lines = ''.join(f'# {line}\n' if line else '#\n' for line in header.splitlines())
    path.write_text(lines + dump_parameters(data))
