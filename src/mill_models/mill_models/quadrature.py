"""Quadrature on sampled signals.

simpson integrates a signal given on an equally spaced grid with an even number of
intervals, as ForceProcessPlant.trace and the β-hold's held plant produce it; the
continuous-time cost J_c of Rubio 2013 eq. (14) is summed from it.
"""

from __future__ import annotations

import numpy as np


def simpson(times: np.ndarray, values: np.ndarray) -> float:
    """Composite Simpson's rule on an equally spaced grid with an even number of intervals."""
    n = len(times) - 1
    if n < 2 or n % 2:
        raise ValueError('simpson needs an even number (>= 2) of intervals')
    h = (times[-1] - times[0]) / n
    return float(
        h / 3.0 * (values[0] + values[-1] + 4.0 * values[1:-1:2].sum() + 2.0 * values[2:-1:2].sum())
    )
