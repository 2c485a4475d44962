"""The identified model as a text table: per axis the model, in the motor's torque units."""

from __future__ import annotations

import math

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
