"""Maharof 2018's figures (docs/papers.md): `offline_sim maharof`, ours beside the paper's."""

from __future__ import annotations

import cmath
import math

from mill_analysis.papers import MAHAROF_READINGS, MAHAROF_TABLES, harmonic_cuts, maharof_metrics
from mill_analysis.readings import overall

from mill_bringup.docs_figures.runs import offline

COLUMNS = ('rmse', 'mte', '26hz', '52hz', '78hz')  # [mm], [mm], [µm] x 3


def figures() -> dict[str, str]:
    out: dict[str, str] = {}
    ours: dict[str, tuple[float, float, tuple[float, ...]]] = {}
    for variant, (p_rmse, p_mte, p_amps) in MAHAROF_TABLES.items():
        rmse, mte, amps = ours[variant] = maharof_metrics(offline('maharof', variant))
        for col, mine, paper in zip(
            COLUMNS, (rmse, mte, *amps), (p_rmse, p_mte, *p_amps), strict=True
        ):
            out[f'{variant}.{col}'] = f'{mine:.4f}' if col in ('rmse', 'mte') else f'{mine:.3f}'
            out[f'{variant}.{col}.paper'] = (
                f'{paper:.4f}' if col in ('rmse', 'mte') else f'{paper:.3f}'
            )
    # the plain cascade's RMSE and MTE against the paper's [%]
    (rmse, mte, _), (p_rmse, p_mte, _) = ours['pi'], MAHAROF_TABLES['pi']
    out['pi.rmse.off'] = f'{100 * abs(rmse / p_rmse - 1):.1f}'
    out['pi.mte.off'] = f'{100 * abs(mte / p_mte - 1):.1f}'
    every = [m[0] for m in ours.values()]  # the RMSE of each configuration
    out['rmse.min'], out['rmse.max'] = f'{min(every):.4f}', f'{max(every):.4f}'
    # IMBDO + DFO against the plain cascade: the MTE and every harmonic peak [%]
    for who, table in (('ours', ours), ('paper', MAHAROF_TABLES)):
        base, both = table['pi'], table['pi_imbdo_dfo']
        out[f'mte.drop.{who}'] = f'{100 * (1 - both[1] / base[1]):.0f}'
        cuts = [100 * c for c in harmonic_cuts(base[2], both[2])]
        out[f'cut.min.{who}'] = f'{min(cuts):.1f}'
        out[f'cut.max.{who}'] = f'{max(cuts):.1f}'
    # the plain cascade's FFT against Table 2 (the force is calibrated on it) [%]
    for col, mine, paper in zip(COLUMNS[2:], ours['pi'][2], MAHAROF_TABLES['pi'][2], strict=True):
        out[f'pi.{col}.off'] = f'{100 * (mine / paper - 1):+.1f}'.replace('-', '−')
    ratio = ours['pi_imbdo'][2][2] / ours['pi'][2][2]
    out['pi_imbdo.78hz.ratio'] = f'{ratio:.2f}'
    out.update(reading_figures(ours['pi']))
    out.update(one_ms_figures())
    out.update(imbdo_figures())
    # the Q filter's order, not given by the paper: 3 instead of 2
    _, _, amps = maharof_metrics(offline('maharof', 'pi_imbdo', ('x_observer.imbdo.q_order=3',)))
    for col, a in zip(COLUMNS[2:], amps, strict=True):
        out[f'pi_imbdo_q3.{col}'] = f'{a:.3f}'
    return out


def reading_figures(base: tuple[float, float, tuple[float, ...]]) -> dict[str, str]:
    """IMBDO + DFO's harmonic cuts under the other ζ_h of the DFO (variants)."""
    out: dict[str, str] = {}
    verdicts: dict[tuple[str, ...], bool] = {}
    for suffix, _ in MAHAROF_READINGS[0][1][1:]:
        rmse, _, amps = maharof_metrics(offline('maharof', 'pi_imbdo_dfo' + suffix))
        key = suffix.lstrip('_')
        out[f'{key}.rmse'] = f'{rmse:.4f}'
        cuts = harmonic_cuts(base[2], amps)
        for col, c in zip(COLUMNS[2:], cuts, strict=True):
            out[f'{key}.{col}.cut'] = f'{-100 * c:+.0f}'.replace('-', '−')
        verdicts[(suffix,)] = all(c > 0 for c in cuts)
        out[f'{key}.verdict'] = 'agrees' if verdicts[(suffix,)] else 'DISAGREES'
    ours = maharof_metrics(offline('maharof', 'pi_imbdo_dfo'))
    verdicts[('',)] = all(c > 0 for c in harmonic_cuts(base[2], ours[2]))
    out['verdict.peaks'] = overall(verdicts, [MAHAROF_READINGS[0][0]]).split()[0]
    return out


def one_ms_figures() -> dict[str, str]:
    """The plain cascade and IMBDO sampled at 1 ms (variants pi_1ms, pi_imbdo_1ms)."""
    out: dict[str, str] = {}
    for variant in ('pi_1ms', 'pi_imbdo_1ms'):
        _, mte, amps = maharof_metrics(offline('maharof', variant))
        out[f'{variant}.mte'] = f'{mte:.4f}'
        for col, a in zip(COLUMNS[2:], amps, strict=True):
            out[f'{variant}.{col}'] = f'{a:.3f}'
    return out


def imbdo_figures() -> dict[str, str]:
    """What IMBDO does to a disturbance at f with the plant's dead time it does not model:
    |1 − Q(jω) e^{−jωT_d}|, Q = ω_c²/(s + ω_c)², f_c = 90 Hz, T_d = 1.2 ms (eq. (1), (3))."""
    wc, td = 2 * math.pi * 90.0, 0.0012
    out = {}
    for f in (26, 78):
        s = 2j * math.pi * f
        q = wc**2 / (s + wc) ** 2
        late = q * cmath.exp(-s * td)  # the compensation as it reaches the plant
        out[f'imbdo.residual.{f}'] = f'{abs(1 - late):.2f}'
        out[f'imbdo.lag.{f}'] = f'{-math.degrees(cmath.phase(late)):.0f}'
    return out
