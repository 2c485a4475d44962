"""The Bode plot `tune` writes beside the parameter file: per axis the return ratio of the
loop as built, on the axis as it is (the measured response, the fitted model beyond it, or
a two-mass model with half its damping where that is the worse; the rigid model's dashed),
its crossover (green) and gain margin (red) marked."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from mill_bringup.tuning.design import AxisTuning
    from mill_bringup.tuning.margins import Margins


def bode_path(params_file: Path) -> Path:
    return params_file.with_name(params_file.stem + '.bode.png')


def _curve(m: Margins | None) -> tuple[np.ndarray, np.ndarray] | None:
    return m.curve if m is not None and m.curve is not None else None


def plot_bode(path: Path, tuned: dict[str, AxisTuning], T: float) -> None:
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    axes = list(tuned)
    fig, grid = plt.subplots(2, len(axes), figsize=(5 * len(axes), 6), squeeze=False)
    for j, a in enumerate(axes):
        t = tuned[a]
        mag_ax, ph_ax = grid[0][j], grid[1][j]
        shown = [(t.margins, 'rigid model', '--')]
        if t.margins.measured is not None:
            label = 'on the axis (measured response, fitted model beyond)'
            if t.margins.measured.share == 0.0:
                label = 'on the fitted model (a two-mass one with half its damping)'
            shown.append((t.margins.measured, label, '-'))
        for m, label, style in shown:
            curve = _curve(m)
            if curve is None:
                continue
            w, L = curve
            f = w / (2.0 * math.pi)
            mag_ax.semilogx(f, 20.0 * np.log10(np.abs(L)), style, label=label)
            phase = np.degrees(np.unwrap(np.angle(L)))
            # the loop's low-frequency phase is −180° or below (a double integrator and the
            # observer's integral): start it in (−360°, 0°]
            phase -= 360.0 * np.ceil(phase[0] / 360.0)
            ph_ax.semilogx(f, phase, style, label=label)
        on = t.margins.measured or t.margins
        mag_ax.axhline(0.0, color='k', lw=0.5)
        mag_ax.axhline(-on.gain_db if math.isfinite(on.gain_db) else -60, color='r', lw=0.5)
        for odd in (-180.0, -540.0):
            ph_ax.axhline(odd, color='k', lw=0.5)
        if math.isfinite(on.crossover):
            fc = on.crossover / (2.0 * math.pi)
            mag_ax.axvline(fc, color='g', lw=0.5)
            ph_ax.axvline(fc, color='g', lw=0.5)
        mag_ax.set_title(
            f'{a}: ω_c {t.omega_c:.0f} rad/s; PM {on.phase:.0f}°, GM {on.gain_db:.1f} dB'
        )
        mag_ax.set_ylabel('|L| [dB]')
        ph_ax.set_ylabel('∠L [°]')
        ph_ax.set_xlabel('frequency [Hz]')
        for ax in (mag_ax, ph_ax):
            ax.set_xlim(0.5, 0.5 / T)
            ax.grid(True, which='both', lw=0.3)
        mag_ax.set_ylim(-60, 60)
        mag_ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)
