"""Position sensor model: an incremental encoder reads whole counts of its resolution."""

from __future__ import annotations

import math


def quantize(value: float, resolution: float) -> float:
    """Round value to the nearest multiple of resolution; resolution 0 is an ideal sensor.

    Ties go to the even count (Python round), which is deterministic. A
    non-finite value is returned unchanged so that a fault stays visible.
    """
    if isinstance(resolution, bool) or not isinstance(resolution, int | float):
        raise ValueError(f'resolution must be a number, got {resolution!r}')
    if not math.isfinite(resolution) or resolution < 0.0:
        raise ValueError(f'resolution must be finite and >= 0, got {resolution!r}')
    if resolution == 0.0 or not math.isfinite(value):
        return value
    return round(value / resolution) * resolution
