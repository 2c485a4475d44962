"""Every axis of a run's record identified (mill_models.identification), or why not; and
the model each axis's record supports, with why (mill_models.axis_model)."""

from __future__ import annotations

import numpy as np
from mill_models.axis_model import AxisModel, StructureSettings, identify_structure
from mill_models.identification import (
    AxisIdentification,
    FitSettings,
    IdentificationError,
    identify_axis,
)

from mill_analysis.record import RunRecord

# axis -> (model, the positions and commands it was fitted to)
Fits = dict[str, tuple[AxisIdentification, np.ndarray, np.ndarray]]
# axis -> (the chosen model and all that was seen, the positions and commands)
Structures = dict[str, tuple[AxisModel, np.ndarray, np.ndarray]]


def longest_finite(x: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The longest run of samples where both are finite (an axis that tripped ends there)."""
    ok = np.isfinite(x) & np.isfinite(u)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(int), [0]])))
    if not edges.size:
        return x[:0], u[:0]
    starts, stops = edges[::2], edges[1::2]
    i = int(np.argmax(stops - starts))
    return x[starts[i] : stops[i]], u[starts[i] : stops[i]]


def identify_record(
    rec: RunRecord, T: float, axes: list[str], skip: float, settings: FitSettings
) -> tuple[Fits, list[str]]:
    """The fits of the axes that could be identified, and a line for each that could not."""
    keep = rec.t >= skip
    fits: Fits = {}
    failed = []
    for axis in axes:
        i = 'xyz'.index(axis)
        x, u = longest_finite(rec.signals['position'][keep, i], rec.signals['torque'][keep, i])
        try:
            fits[axis] = (identify_axis(x, u, T, settings), x, u)
        except IdentificationError as exc:
            failed.append(f'{axis}: {exc}')
    return fits, failed


def axis_series(rec: RunRecord, axis: str, skip: float) -> tuple[np.ndarray, np.ndarray]:
    keep = rec.t >= skip
    i = 'xyz'.index(axis)
    return longest_finite(rec.signals['position'][keep, i], rec.signals['torque'][keep, i])


def structure_record(
    rec: RunRecord, T: float, axes: list[str], skip: float, settings: StructureSettings
) -> Structures:
    """The model each axis's record supports (rigid, two-mass or none) and why."""
    out: Structures = {}
    for axis in axes:
        x, u = axis_series(rec, axis, skip)
        out[axis] = (identify_structure(x, u, T, settings), x, u)
    return out
