"""The readings and settings a paper's verdicts rest on, printed before its report. ROS-free."""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from typing import Any

# The parameters a variant's figures rest on, per paper (what the verdicts are a reading of).
Parameters = Mapping[str, Mapping[str, Mapping[str, Any]]]  # variant → node → name → value


def hatwesh_readings(parameters: Parameters) -> str:
    """One line per variant: the readings of Hatwesh 2013 its law runs with."""
    lines = []
    for name, nodes in parameters.items():
        p = nodes.get('x_controller', {})
        law = p.get('controller')
        if law == 'adaptive_pi':
            load = p['adaptive_pi.load_term']
            lines.append(
                f'reading of {name}: RLS '
                + ('with the load term c' if load else 'of eq. (12) as printed, no load term')
                + f' (adaptive_pi.load_term), phase-margin rule {p["adaptive_pi.design_rule"]} '
                f'(adaptive_pi.design_rule), φ_m {p["adaptive_pi.phase_margin"]:g}°, velocity '
                f'{p["adaptive_pi.velocity_source"]} (adaptive_pi.velocity_source)'
            )
        elif law == 'machine_pi':
            lines.append(
                f'reading of {name}: Table 1 gains in {p["machine_pi.velocity_unit"]} '
                f'(machine_pi.velocity_unit), velocity {p["machine_pi.velocity_source"]} '
                '(machine_pi.velocity_source)'
            )
    return '\n'.join(lines)


# The settings every paper's verdicts rest on (node, parameter, what it is), printed before
# the report with the value each variant ran with: the sample period and each reading that
# departs from, or is not given by, the paper (docs/papers.md has the table of each).
SETTINGS: dict[str, tuple[tuple[str, str, str], ...]] = {
    'beltran': (
        ('plant', 'sample_period', 'sample period [s] (paper: not given)'),
        (
            'plant',
            'kline.specific_energy',
            'u_s [J/m³] (read as 0.5 hp·min/in³ = 1.37e9; printed 0.5 kW/(cm³/min) = 3e10)',
        ),
        ('plant', 'screw_damping', 'c_t [N·s/m] (translational; literal c_t/a² is unstable)'),
        ('x_observer', 'gpi.discretisation', "observer discretisation (paper's is continuous)"),
    ),
    'chavez_conde': (
        ('plant', 'sample_period', 'sample period [s] (paper: fixed step 1e-3)'),
        ('plant', 'screw_damping', 'c_t [N·s/m] (translational; literal c_t/a² = 986960)'),
        ('plant', 'friction_reversal', 'friction reversal (paper: not said)'),
        ('plant', 'kline.specific_energy', 'u_s of the Fig. 2 force [J/m³] (Beltrán reading)'),
    ),
    'maharof': (
        ('plant', 'sample_period', 'sample period [s] (paper: not given)'),
        ('x_observer', 'imbdo_dfo.zeta_h', 'DFO ζ_h (ours; paper prints no DFO gains)'),
        ('x_observer', 'imbdo.q_order', 'IMBDO Q order (paper: not given)'),
        ('plant', 'harmonic.amplitudes', 'synthetic force [N] (calibrated on the plain loop)'),
    ),
    'rubio': (
        ('trajectory', 'sample_period', 'sample period [s] (paper: one revolution, 60/715)'),
        ('force_controller', 'multi_model_1.index_signal', 'what eq. (13) compares, scheme 1'),
        ('force_controller', 'multi_model_2.index_signal', 'what eq. (13) compares, scheme 2'),
        ('force_controller', 'force_control.observer_degree', 'observer polynomial degree (ours)'),
        (
            'force_controller',
            'force_control.observer_time_constant',
            'observer pole time constant [s] (ours; 0 = τ_c)',
        ),
        ('force_process', 'force_process.depth_profile', 'depth profile [s, mm] (ours)'),
    ),
}


def settings_lines(paper: str, parameters: Parameters) -> str:
    """One line per setting: the value most variants ran with, and the variants that ran
    with another."""
    lines = []
    for node, name, what in SETTINGS.get(paper, ()):
        values = {v: nodes.get(node, {}).get(name) for v, nodes in parameters.items()}
        values = {v: x for v, x in values.items() if x is not None}
        if not values:
            continue
        texts = [repr(x) for x in values.values()]
        common = max(texts, key=texts.count)
        others = [f'{v} {t}' for v, t in zip(values, texts, strict=True) if t != common]
        lines.append(
            f'setting {node}.{name}, {what}: {common}'
            + (f' (other: {", ".join(others)})' if others else '')
        )
    return '\n'.join(lines)


READINGS: dict[str, Callable[[Parameters], str]] = {
    'hatwesh': hatwesh_readings,
    'hatwesh_velocity': hatwesh_readings,
    **{paper: functools.partial(settings_lines, paper) for paper in SETTINGS},
}
