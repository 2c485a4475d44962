"""Hatwesh 2013's figures (docs/papers.md): the phase margins (`python -m
mill_controllers.hatwesh_margins`, on the exactly sampled drive, no runs), the velocity-step
experiment (`offline_sim hatwesh_velocity --skip 0`, per reading) and the position move
(`offline_sim hatwesh --skip 0`)."""

from __future__ import annotations

import math

from mill_analysis.papers import (
    HATWESH_BAND,
    HATWESH_MOVES,
    HV_BAND,
    HV_LOAD,
    HV_PHASES,
    HV_STEP,
    PhaseMetrics,
    hv_verdicts,
    load_response,
    move_metrics,
    phase_metrics,
)
from mill_controllers.phase_margin import DESIGN_RULES, design_pi

from mill_bringup.docs_figures.runs import offline
from mill_controllers import hatwesh_margins as hm


def margin_figures() -> dict[str, str]:
    out: dict[str, str] = {}
    gains: dict[str, float] = {}  # K_p by figure key
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
                gains[key] = kp
                out[f'{key}.w_gc'] = f'{w_gc:.0f}'
                out[f'{key}.k_p'] = f'{kp:.2f}'
                out[f'{key}.margin'] = 'unstable' if math.isnan(w) else f'{pm:.1f}'
    # the machine PI: its loop in Hz, and the phase the backward difference costs it [°]
    w, pm = hm.margin(hm.series(hm.machine_pi(), hm.plant('difference')))
    out['machine_pi.difference.crossover_hz'] = f'{w / (2 * math.pi):.0f}'
    pm_sampled = hm.margin(hm.series(hm.machine_pi(), hm.plant('sampled')))[1]
    out['machine_pi.difference.cost'] = f'{pm_sampled - pm:.0f}'
    # the discrete rule's K_p over the continuous rule's (the hold's magnitude)
    for phi in (25, 60):
        ratio = gains[f'difference.{phi}.discrete'] / gains[f'difference.{phi}.continuous']
        out[f'difference.{phi}.k_p_ratio'] = f'{ratio:.2f}'
    return out


VELOCITY = 'hatwesh_velocity'
PHASES = {'nominal': 'nominal', 'after inertia': 'inertia', 'under load': 'load'}
# The readings of the verdict table: its column → the override (none: the defaults).
READINGS = {
    'defaults': '',
    'no_load_term': 'x_controller.adaptive_pi.load_term=false',
    'discrete': 'x_controller.adaptive_pi.design_rule=discrete',
}


def _phases(variant: str, override: str = '') -> dict[str, PhaseMetrics]:
    rec = offline(VELOCITY, variant, (override,) if override else ())
    return {k: phase_metrics(rec, a, b, HV_BAND) for k, (a, b) in HV_PHASES.items()}


def velocity_figures() -> dict[str, str]:
    """`offline_sim hatwesh_velocity --skip 0`: the table, the load response and, per
    reading, the claims' verdicts and the figures they rest on."""
    out: dict[str, str] = {'band': f'{HV_BAND * HV_STEP * 1e3:g}'}  # [mm/s]
    for variant in ('machine_pi', 'adaptive_pi', 'adaptive_pi_pm25'):
        for phase, m in _phases(variant).items():
            key = f'{variant}.{PHASES[phase]}'
            out[f'{key}.overshoot'] = f'{m.overshoot:.2f}'  # [%]
            out[f'{key}.settling'] = f'{m.settling_time * 1e3:.2f}'  # [ms]
            out[f'{key}.iae'] = f'{m.iae:.3f}'  # [µm]
            out[f'{key}.max_u'] = f'{m.max_command:.2f}'  # [V]
        drop, back = load_response(offline(VELOCITY, variant), *HV_LOAD, HV_BAND * HV_STEP)
        out[f'{variant}.load.drop'] = f'{drop:.3f}'  # [mm/s]
        if 0.0 < back < math.inf:
            out[f'{variant}.load.back'] = f'{back * 1e3:.2f}'  # [ms]
    n, a, b = 'nominal', 'after inertia', 'under load'
    for reading, override in READINGS.items():
        ours = {'machine_pi': _phases('machine_pi')}  # the override leaves it as it is
        for variant in ('adaptive_pi', 'adaptive_pi_pm25'):
            ours[variant] = _phases(variant, override)
        mach, ada, pm25 = ours['machine_pi'], ours['adaptive_pi'], ours['adaptive_pi_pm25']
        for i, holds in enumerate(hv_verdicts(ours)):
            out[f'{reading}.claim{i + 1}'] = 'agrees' if holds else 'DISAGREES'
        out[f'{reading}.pm25.overshoot'] = f'{pm25[n].overshoot:.1f}'
        out[f'{reading}.pm25.settling'] = f'{pm25[n].settling_time * 1e3:.2f}'
        out[f'{reading}.nominal.overshoot1'] = f'{ada[n].overshoot:.1f}'
        out[f'{reading}.nominal.overshoot2'] = f'{ada[n].overshoot:.2f}'
        out[f'{reading}.nominal.settling'] = f'{ada[n].settling_time * 1e3:.2f}'
        out[f'{reading}.nominal.iae'] = f'{ada[n].iae:.3f}'
        out[f'{reading}.inertia.ratio'] = f'{ada[a].iae / ada[n].iae:.3f}'
        out[f'{reading}.load.ratio'] = f'{ada[b].iae / ada[a].iae:.3f}'
        out[f'{reading}.inertia.overshoot'] = f'{ada[a].overshoot:.1f}'
        out[f'{reading}.load.overshoot'] = f'{ada[b].overshoot:.1f}'
    out['machine_pi.inertia.ratio'] = f'{mach[a].iae / mach[n].iae:.3f}'
    out['machine_pi.load.ratio'] = f'{mach[b].iae / mach[a].iae:.3f}'
    return out


POSITION = 'hatwesh'
PM25 = 'x_controller.adaptive_pi.phase_margin=25.0'


def move_figures() -> dict[str, str]:
    """`offline_sim hatwesh --skip 0` (and adaptive_pi at 25°): each move's figures."""
    out: dict[str, str] = {}
    runs = {v: offline(POSITION, v) for v in ('machine_pi', 'adaptive_pi', 'adaptive_pi_rls')}
    runs['adaptive_pi_pm25'] = offline(POSITION, 'adaptive_pi', (PM25,))
    for variant, rec in runs.items():
        m = {k: move_metrics(rec, *v, HATWESH_BAND) for k, v in HATWESH_MOVES.items()}
        for move, metrics in m.items():
            key = f'{variant}.{move}'
            out[f'{key}.iae'] = f'{metrics.iae:.6f}'  # [mm s]
            if variant != 'adaptive_pi_pm25':
                out[f'{key}.overshoot'] = f'{metrics.overshoot:.3f}'.rstrip('0').rstrip('.')
                if math.isfinite(metrics.settling_time):
                    out[f'{key}.settling'] = f'{metrics.settling_time * 1e3:.0f}'  # [ms]
        if variant != 'adaptive_pi_pm25':
            out[f'{variant}.ratio'] = f'{m["after"].iae / m["before"].iae:.3f}'
    del out['adaptive_pi_rls.ratio']  # not quoted
    return out
