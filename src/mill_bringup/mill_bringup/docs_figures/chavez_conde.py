"""Chávez-Conde's figures (docs/papers.md): `offline_sim chavez_conde --skip 0`, the
constants of the paper's setting computed from the scenario's parameters, and the probes
the text quotes (another sampling, no force, the default friction reversal)."""

from __future__ import annotations

import math

import numpy as np
from mill_analysis.chavez_conde import (
    READINGS,
    chatters,
    reading_verdicts,
    reduces,
    torque_metrics,
    tracking_metrics,
    trip,
)
from mill_analysis.readings import overall
from mill_controllers.gpi_controller import GpiController
from mill_controllers.sliding_gpi import SlidingGpiController
from mill_plant.config import build_axis_model

from mill_bringup import scenario
from mill_bringup.docs_figures.runs import law_values, offline, sig

NAME = 'chavez_conde'
X = 0
FINE = '*.sample_period=0.00005'  # the probes at 0.05 ms


def figures() -> dict[str, str]:
    """The table (every variant) and the ratios and constants the claims quote."""
    out: dict[str, str] = {}
    ours = {}
    trips: dict[str, tuple[float, float] | None] = {}
    readings = {v for _, values in READINGS for v, _ in values if v}
    for variant in scenario.load(NAME).variants:
        rec = offline(NAME, variant)
        peak, rms = ours[variant] = tracking_metrics(rec)
        top, at_top, chatter = torque_metrics(rec)
        if tripped := trips.setdefault(variant, trip(rec)):  # braked: no tracking figures
            out[f'{variant}.trip_t'], out[f'{variant}.trip_e'] = sig(tripped[0]), sig(tripped[1])
        else:
            out[f'{variant}.max_e'] = sig(peak)  # [mm]
            out[f'{variant}.rms_e'] = sig(rms)
        if any(r in variant for r in readings):  # the readings table quotes the errors only
            continue
        out[f'{variant}.max_tau'] = sig(top)  # [N m]
        out[f'{variant}.rms_dtau'] = sig(chatter, 3)
        if variant == 'gpi':
            chatter_gpi = chatter
        if variant == 'sliding_gpi':
            out['sliding_gpi.chatter_ratio'] = f'{chatter / chatter_gpi:.2g}'.replace('e+0', 'e')
            out['verdict.chatter'] = chatters(chatter / chatter_gpi)
        if variant.endswith('_limited') and variant.startswith('sliding'):
            out[f'{variant}.at_max'] = f'{at_top:.0f}'  # [% of samples]
    for suffix in ('', '_zoh', '_flexible'):
        gpi, sliding = 'gpi' + suffix, 'sliding_gpi' + suffix
        out[f'verdict{suffix}'] = reduces(ours[gpi], ours[sliding], trips[gpi], trips[sliding])
    verdicts = reading_verdicts(ours, trips)
    for combo, holds in verdicts.items():
        out[f'reading.{"".join(combo).lstrip("_") or "ours"}'] = 'agrees' if holds else 'DISAGREES'
    out['verdict.readings'] = overall(verdicts, [n for n, _ in READINGS]).split()[0]
    for suffix in ('', '_zoh'):
        (pg, rg), (ps, rs) = ours['gpi' + suffix], ours['sliding_gpi' + suffix]
        out[f'ratio{suffix}.rms'] = f'{rs / rg:.2f}'
        out[f'ratio{suffix}.max'] = f'{ps / pg:.2f}' if ps < pg else f'{ps / pg:.1f}'
    out.update(constants())
    out['flexible.mode_hz'] = f'{flexible_modes()[-1]:.0f}'
    return out


def flexible_modes() -> list[float]:
    """The flexible x axis's modes [Hz], ascending: the eigenvalues of its equations
    linearised while the carriage slides (friction then a constant)."""
    model = build_axis_model(scenario.load(NAME).variant('gpi_flexible').parameters('plant'), X)
    n = len(model.initial_state(0.0))
    rest = np.asarray(model.derivative([0.0] * n, 0.0, 0.0, 1.0))
    jacobian = np.column_stack(
        [np.asarray(model.derivative(list(np.eye(n)[j]), 0.0, 0.0, 1.0)) - rest for j in range(n)]
    )
    return sorted(w / (2 * math.pi) for w in np.linalg.eigvals(jacobian).imag if w > 0)


def constants() -> dict[str, str]:
    """η1, the mean force, the laws' steady errors under it: from the parameters."""
    scen = scenario.load(NAME)
    plant, law = scen.parameters('plant'), scen.parameters('x_controller')
    a = plant['pitch'][X] / (2 * math.pi)  # [m/rad]
    eta1 = plant['mass'][X] + plant['screw_inertia'][X] / a**2
    eta2 = plant['cart_damping'][X] + plant['screw_damping'][X]
    literal = plant['cart_damping'][X] + plant['screw_damping'][X] / a**2
    teeth, rpm = plant['kline.teeth'], plant['kline.spindle_speed']
    feed = plant['kline.program_feed_rate'] * 60.0 / (rpm * teeth)  # [m/tooth]
    depth = plant['kline.workpiece_top'] - plant['kline.program'][2]
    force = 0.5 * plant['kline.specific_energy'] * depth * feed
    b, T = law['input_gain'], scen.parameters('plant')['sample_period']
    gpi = GpiController.from_parameters(b, T, law_values(law, 'gpi'))
    sliding = SlidingGpiController.from_parameters(b, T, law_values(law, 'sliding_gpi'))
    a0, _, a2 = gpi.alphas
    kappa = law['gpi.damping_rate']
    s0 = sliding.surface_gains[0]
    mu_gamma = law['sliding_gpi.mu'] * law['sliding_gpi.gamma']
    return {
        'eta1': f'{eta1:.2f}',
        'eta2': f'{eta2:g}',
        'eta2_literal': f'{literal:.2g}'.replace('e+0', 'e'),
        'kappa': f'{kappa:.5g}',
        'force.mean': f'{force:.1f}',
        'force.hz': f'{rpm / 60 * teeth:.0f}',
        'force.tooth_ms': f'{60e3 / (rpm * teeth):.1f}',
        'gpi.a2_minus_kappa': f'{a2 - kappa:.0f}',
        'gpi.a0': f'{a0:.0f}',
        'gpi.steady_e': sig((a2 - kappa) * force / (eta1 * a0) * 1e3, 3),  # [mm]
        'sliding.a0': f'{s0:.0f}',
        'sliding.steady_e': sig(force / (eta1 * s0) * 1e3, 3),
        'sliding.mu_gamma': f'{mu_gamma:g}',
        'sliding.switching': f'{mu_gamma / b:.0f}',  # [N m]
        'sliding.zoh_kick': f'{mu_gamma * 1e-3:.2f}',  # [m/s per 1 ms sample]
    }


def probe_figures() -> dict[str, str]:
    """The sliding law sampled at 0.05 ms, without the force and with the plant's default
    handling of a reversal; the GPI law on the flexible axis at the 1 ms ZOH."""
    out: dict[str, str] = {}
    peak, rms = tracking_metrics(offline(NAME, 'sliding_gpi', (FINE,)))
    out['sliding_fine.max_e'], out['sliding_fine.rms_e'] = sig(peak, 3), sig(rms, 3)
    peak, rms = tracking_metrics(offline(NAME, 'sliding_gpi', ('plant.cutting_model=none',)))
    out['sliding_no_force.max_e'], out['sliding_no_force.rms_e'] = sig(peak, 3), sig(rms, 2)
    stop = offline(NAME, 'sliding_gpi', (FINE, 'plant.friction_reversal=stop'))
    out['sliding_fine_stop.max_e'] = sig(tracking_metrics(stop)[0], 2)
    zoh = (
        'x_controller.gpi.discretisation=zoh',
        '*.sample_period=0.001',
        '*.design_period=0.001',
        'plant.substeps=20',
    )
    out['gpi_flexible_zoh.max_e'] = sig(tracking_metrics(offline(NAME, 'gpi_flexible', zoh))[0], 2)
    return out
