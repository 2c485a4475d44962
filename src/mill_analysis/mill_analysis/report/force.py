"""The report of a force job's bag (Rubio 2013): J_c of eq. (14), the override, the force.

A force job has no axis states: its bag holds the force samples, the force stream between
them, the overrides and the force controller's state (mill_analysis.force_record reads
them). Several bags go side by side as one row each.
"""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import numpy as np
from mill_models.reference_model import ContinuousReference

from mill_analysis.bag_meta import loss_lines
from mill_analysis.force_record import ForceBagRun


def _samples(run: ForceBagRun) -> str:
    """The samples the bag holds, of the job's when it holds fewer."""
    return f'{run.held}' if run.held == run.samples else f'{run.held}/{run.samples}'


def _row(label: str, run: ForceBagRun) -> str:
    rec = run.record
    betas = ', '.join(f'{b:g}' for b in dict.fromkeys(rec.beta[np.isfinite(rec.beta)].tolist()))
    return (
        f'{label:<20} {_samples(run):>7} {run.period * 1e3:>9.4f} {rec.j_c:>12.6g} '
        f'{np.nanmean(rec.override):>9.4f} {np.nanmin(rec.override):>8.4f} '
        f'{np.nanmax(rec.override):>8.4f}  {betas}'
    )


HEAD = (
    f'{"run":<20} {"samples":>7} {"T [ms]":>9} {"J_c [N² s]":>12} {"override":>9} '
    f'{"min":>8} {"max":>8}  active β'
)


def force_table(runs: list[tuple[str, ForceBagRun]]) -> str:
    lines = [
        'force job (Rubio 2013): J_c of eq. (14) from the recorded force stream against the '
        'reference model eq. (7); the override per sample',
        HEAD,
    ]
    lines += [_row(label, run) for label, run in runs]
    for label, run in runs:
        lines += [f'{label}: {line}' for line in loss_lines(run.missing, run.record.gaps)]
        for note in run.notes:
            lines.append(f'{label}: note: {note}')
    return '\n'.join(lines)


def force_markdown(
    runs: list[tuple[str, ForceBagRun]], figures: list[tuple[str, str]], argv: list[str]
) -> str:
    lines = [
        '# Force job report',
        '',
        f'`report {" ".join(argv)}`, {dt.datetime.now():%Y-%m-%d %H:%M}',
        '',
        '| run | bag | samples | T [ms] | F_r [N] | ξ, ω_n [rad/s] | J_c [N²·s] | mean override |',
        '|---|---|---|---|---|---|---|---|',
    ]
    for label, run in runs:
        lines.append(
            f'| {label} | `{run.path}` | {_samples(run)} | {run.period * 1e3:.4f} | '
            f'{run.reference_force:g} | {run.damping:g}, {run.omega_n:.4g} | '
            f'{run.record.j_c:.6g} | {np.nanmean(run.record.override):.4f} |'
        )
    notes = [
        f'- {label}: {n}'
        for label, run in runs
        for n in [*loss_lines(run.missing, run.record.gaps), *run.notes]
    ]
    if notes:
        lines += ['', *notes]
    for name, title in figures:
        lines += ['', f'## {title}', '', f'![{title}]({name})']
    return '\n'.join(lines)


def force_figure(runs: list[tuple[str, ForceBagRun]], out: Path) -> list[tuple[str, str]]:
    """The force against the reference model's response, and the override, per run."""
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 1, figsize=(9.0, 6.0), sharex=True)
    for label, run in runs:
        rec = run.record
        t = rec.trace_ns / 1e9
        (line,) = axes[0].plot(t, rec.trace_force, lw=0.8, label=f'{label} F_p')
        ref = ContinuousReference(run.damping, run.omega_n)
        ref.begin(run.reference_force)
        axes[0].plot(t, ref.values(t), lw=0.8, ls='--', color=line.get_color(), alpha=0.6)
        axes[1].step(rec.t, rec.override, where='post', lw=0.9, label=label)
    axes[0].set_ylabel('force [N] (dashed: F_pm)')
    axes[1].set_ylabel('feed override [-]')
    axes[1].set_xlabel('t [s]')
    for a in axes:
        a.grid(True, alpha=0.3)
        a.legend(fontsize=8)
    fig.tight_layout()
    name = 'force.png'
    fig.savefig(out / name, dpi=110)
    plt.close(fig)
    return [(name, 'Force against the reference model, and the feed override')]
