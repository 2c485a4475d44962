"""Rubio 2013's figures (docs/papers.md): `offline_sim rubio` and `python -m
mill_bringup.force_loop` (the sweep over fixed β and the reordered depth profile)."""

from __future__ import annotations

import numpy as np
from mill_analysis.papers import RUBIO_READINGS, RUBIO_SCHEME_CLAIMS, rubio_reading_cases
from mill_analysis.readings import overall
from mill_models.force_process import ForceProcessModel, ForceProcessParams

from mill_bringup import force_loop, scenario
from mill_bringup.docs_figures.runs import offline

VARIANTS = ('zoh', 'beta_neg0.3', 'scheme1', 'scheme2')
SWEEP = (-1.0, -0.7, -0.3, 0.0, 0.3, 1.0)  # the columns of the docs' table
REORDERED = [0.0, 2.0, 2.0, 1.5, 4.0, 3.5, 6.0, 3.0, 8.0, 2.0]  # --depth-profile 0,2,2,1.5,...
ONE_STEP = {'up': [0.0, 2.0, 5.0, 3.0], 'down': [0.0, 3.0, 5.0, 2.0]}  # a single depth step


def joules(x: float) -> str:
    """J_c [N²·s] in groups of three digits: 469 648."""
    return f'{x:,.0f}'.replace(',', ' ')


def percent(x: float) -> str:
    return f'{100 * x:+.2f}'.replace('-', '−')


def figures() -> dict[str, str]:
    out: dict[str, str] = {}
    zoh = offline('rubio', 'zoh').j_c
    for variant in VARIANTS:
        j_c = offline('rubio', variant).j_c
        out[f'{variant}.j_c'] = joules(j_c)
        if variant != 'zoh':
            out[f'{variant}.vs_zoh'] = percent(j_c / zoh - 1)
    for beta, j_c in zip(SWEEP, force_loop.sweep(SWEEP), strict=True):
        out[f'sweep.{beta:g}'] = joules(j_c)
    negative = force_loop.sweep([b / 10 for b in range(-10, 0)])
    out['sweep.best_negative'] = f'{100 * (1 - min(negative) / zoh):.2f}'
    model = ForceProcessModel(ForceProcessParams(depth_profile=REORDERED))
    cases = force_loop.paper_cases(model=model)
    r_zoh = cases['ZOH (β = 0)'].j_c
    for key, name in zip(VARIANTS, force_loop.PAPER_CASES, strict=True):
        out[f'reordered.{key}.j_c'] = joules(cases[name].j_c)
    out['reordered.scheme1.vs_zoh'] = percent(cases['scheme 1'].j_c / r_zoh - 1)
    r_negative = force_loop.sweep([b / 10 for b in range(-10, 0)], model=model)
    out['reordered.best_negative'] = f'{100 * (1 - min(r_negative) / r_zoh):.2f}'
    out['scheme2.beta_max'] = f'{np.abs(offline("rubio", "scheme2").beta).max():g}'
    for key, profile in ONE_STEP.items():  # β = −0.5 against the ZOH [% worse]
        neg, zoh_j_c = force_loop.sweep(
            [-0.5, 0.0], model=ForceProcessModel(ForceProcessParams(depth_profile=profile))
        )
        out[f'one_step.{key}.beta_neg0.5'] = f'{100 * (neg / zoh_j_c - 1):.2f}'
    out.update(reading_figures())
    return out


def reading_figures() -> dict[str, str]:
    """The schemes against the ZOH under each reading (variants of `offline_sim rubio`)."""
    out: dict[str, str] = {}
    records = {v: offline('rubio', v) for v in scenario.load('rubio').variants}
    cases = rubio_reading_cases(records)
    names = [name for name, _ in RUBIO_READINGS]
    for i, (scheme, _, holds) in enumerate(RUBIO_SCHEME_CLAIMS):
        for combo, (zoh, *schemes) in cases.items():
            key = ''.join(combo).lstrip('_') or 'ours'
            out[f'reading.{key}.{scheme}.vs_zoh'] = percent(schemes[i] / zoh - 1)
            out[f'reading.{key}.{scheme}'] = 'agrees' if holds(schemes[i], zoh) else 'disagrees'
        verdicts = {c: holds(j[1 + i], j[0]) for c, j in cases.items()}
        out[f'verdict.{scheme}'] = overall(verdicts, names).split()[0].lower()
    return out
