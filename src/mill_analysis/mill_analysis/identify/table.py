"""The identified model as a text table: per axis the model, in the motor's torque units."""

from __future__ import annotations

import math

from mill_models.axis_model import AxisModel
from mill_models.identification import AxisIdentification


def table(models: dict[str, AxisIdentification], pitch: float | None = None) -> str:
    """One row per axis; with the screw pitch [m/rev], the forces in N as well."""
    rows = [
        '| axis | delay [samples] | b [m/s² per N·m] | viscous [N·m per m/s] | Coulomb [N·m] | '
        'load (hold_torque) [N·m] | RMS fit / held out [µm] |',
        '|---|---|---|---|---|---|---|',
    ]
    for axis, m in models.items():
        rows.append(
            f'| {axis} | {m.delay} | {m.b.text()} | {m.torque("alpha").text()} | '
            f'{m.torque("beta").text()} | {m.torque("gamma").text()} | '
            f'{1e6 * m.fit_rms:.3g} / {1e6 * m.validation_rms:.3g} |'
        )
    if pitch:
        lead = pitch / (2.0 * math.pi)
        rows += [
            '',
            f'With a {1e3 * pitch:g} mm pitch (lead a = {1e6 * lead:.4g} µm/rad): forces on the '
            'carriage',
            '',
            '| axis | m_e = 1/(a·b) [kg] | viscous c_e [N·s/m] | Coulomb μ [N] | load [N] |',
            '|---|---|---|---|---|',
        ]
        for axis, m in models.items():
            mass = 1.0 / (lead * m.b.value)
            rows.append(
                f'| {axis} | {mass:.4g} | {m.alpha.value * mass:.4g} | '
                f'{m.beta.value * mass:.4g} | {m.gamma.value * mass:.4g} |'
            )
    return '\n'.join(rows)


def structure_table(models: dict[str, AxisModel], pitch: float | None = None) -> str:
    """Per axis the model chosen and what decided it: resonance, low-speed friction, backlash,
    the band the response covered; then the reason, one line per axis."""
    unit = 'N' if pitch else 'N·m'
    rows = [
        f'| axis | model | resonance [Hz] (ζ) | breakaway / sliding friction [{unit}] | '
        'Stribeck speed [mm/s] | backlash [µm] | response fitted / excitation [Hz] |',
        '|---|---|---|---|---|---|---|',
    ]
    for axis, m in models.items():
        tm = m.two_mass
        resonance = 'none'
        if tm is not None:
            hz = tm.resonance_hz
            spread = hz * tm.omega_r.half_width / tm.omega_r.value
            resonance = (
                f'{hz:.3g} ± {spread:.2g} ({tm.zeta.value:.2g}); anti {tm.anti_resonance_hz:.3g}'
            )
        friction = speed = '-'
        if m.friction is not None and m.rigid is not None:
            # as the motor torque that balances it (÷ b), with the pitch as the force (÷ a)
            scale = 1.0 / m.rigid.b.value / (pitch / (2.0 * math.pi) if pitch else 1.0)
            f = m.friction
            friction = f'{f.static.text(scale)} / {f.coulomb.text(scale)}'
            speed = f.speed.text(1e3) if f.speed is not None else 'no Stribeck effect'
        backlash = '-'
        if m.backlash is not None and math.isfinite(m.backlash.width.value):
            backlash = m.backlash.width.text(1e6, 3) if m.backlash.present else 'none'
        band = '-'
        if m.response is not None and m.response.bins:
            lo, hi = m.response.band
            elo, ehi = m.response.excitation_band
            band = f'{lo:.0f}-{hi:.0f} / {elo:.2g}-{ehi:.3g}'
        rows.append(
            f'| {axis} | {m.model} | {resonance} | {friction} | {speed} | {backlash} | {band} |'
        )
    rows.append('')
    rows += [m.line(axis) for axis, m in models.items()]
    return '\n'.join(rows)
