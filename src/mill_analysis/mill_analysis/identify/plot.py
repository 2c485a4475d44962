"""Model against measurement on the windows the fit did not use, one row per axis."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from mill_models.identification import (
    AxisIdentification,
    FitSettings,
    held_out_windows,
    predict_window,
)

SHOWN = 6  # held-out windows drawn per axis


def plot(path: Path, fits: dict[str, tuple[AxisIdentification, np.ndarray, np.ndarray]]) -> None:
    """fits: axis → (model, positions, commands) as fitted."""
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    fig, rows = plt.subplots(len(fits), 2, figsize=(11, 2.8 * len(fits)), squeeze=False)
    for (axis, (m, x, u)), (ax_pos, ax_err) in zip(fits.items(), rows, strict=True):
        offset = 0.0
        for w in held_out_windows(m, x, FitSettings())[:SHOWN]:
            t, measured, predicted = predict_window(m, x, u, w)
            ax_pos.plot(offset + t, 1e3 * measured, 'k.', ms=1.5)
            ax_pos.plot(offset + t, 1e3 * predicted, 'C1-', lw=1)
            ax_err.plot(offset + t, 1e6 * (measured - predicted), 'C0-', lw=0.8)
            offset += t[-1] + 0.05
        ax_pos.set_title(f'{axis}: held-out windows, measured (dots) and model (line)', fontsize=9)
        ax_pos.set_ylabel('x − x(0) [mm]')
        ax_err.set_title(f'{axis}: measured − model', fontsize=9)
        ax_err.set_ylabel('[µm]')
    for ax in rows[-1]:
        ax.set_xlabel('time in the windows, laid end to end [s]')
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
