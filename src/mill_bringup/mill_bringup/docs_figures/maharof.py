"""Maharof 2018's figures (docs/papers.md): `offline_sim maharof`, ours beside the paper's."""

from __future__ import annotations

from mill_analysis.papers import MAHAROF_TABLES, harmonic_cuts, maharof_metrics

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
    return out
