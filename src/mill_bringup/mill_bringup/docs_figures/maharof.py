"""Maharof 2018's figures (docs/papers.md): `offline_sim maharof`, ours beside the paper's."""

from __future__ import annotations

from mill_analysis.papers import MAHAROF_TABLES, maharof_metrics

from mill_bringup.docs_figures.runs import offline

COLUMNS = ('rmse', 'mte', '26hz', '52hz', '78hz')  # [mm], [mm], [µm] x 3


def figures() -> dict[str, str]:
    out: dict[str, str] = {}
    for variant, (p_rmse, p_mte, p_amps) in MAHAROF_TABLES.items():
        rmse, mte, amps = maharof_metrics(offline('maharof', variant))
        for col, ours, paper in zip(
            COLUMNS, (rmse, mte, *amps), (p_rmse, p_mte, *p_amps), strict=True
        ):
            out[f'{variant}.{col}'] = f'{ours:.4f}' if col in ('rmse', 'mte') else f'{ours:.3f}'
            out[f'{variant}.{col}.paper'] = (
                f'{paper:.4f}' if col in ('rmse', 'mte') else f'{paper:.3f}'
            )
    return out
