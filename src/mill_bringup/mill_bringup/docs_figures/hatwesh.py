"""Hatwesh 2013's phase-margin figures (docs/papers.md): `python -m
mill_controllers.hatwesh_margins`, on the exactly sampled drive (no runs)."""

from __future__ import annotations

import math

from mill_controllers.phase_margin import DESIGN_RULES, design_pi

from mill_controllers import hatwesh_margins as hm


def margin_figures() -> dict[str, str]:
    out: dict[str, str] = {}
    for velocity in hm.VELOCITIES:
        w, pm = hm.margin(hm.series(hm.machine_pi(), hm.plant(velocity)))
        out[f'machine_pi.{velocity}.crossover'] = f'{w:.0f}'
        out[f'machine_pi.{velocity}.margin'] = f'{pm:.1f}'
        model = hm.drive_model(velocity)
        for phi in (25, 60):
            for rule in DESIGN_RULES:
                kp, ki, w_gc = design_pi(rule, model, math.radians(phi), hm.T)
                w, pm = hm.margin(hm.series(hm.pi(kp, ki), hm.plant(velocity)))
                key = f'{velocity}.{phi}.{rule}'
                out[f'{key}.w_gc'] = f'{w_gc:.0f}'
                out[f'{key}.k_p'] = f'{kp:.2f}'
                out[f'{key}.margin'] = 'unstable' if math.isnan(w) else f'{pm:.1f}'
    return out
