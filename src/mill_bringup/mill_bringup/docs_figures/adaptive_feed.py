"""The adaptive-feed job's figures (docs/papers.md): `offline_sim slotting_adaptive_feed`
(the offline twin of `run_scenario slotting_adaptive_feed --compare-offline`), and the same
with the law's ratio r of an earlier Kline model."""

from __future__ import annotations

import math

import numpy as np
from mill_analysis.record import FORCE_CONTROL

from mill_bringup import scenario
from mill_bringup.docs_figures.runs import offline
from mill_bringup.jobs.axis import AxisJob, depth_stretches
from mill_bringup.jobs.registry import job_for

NAME = 'slotting_adaptive_feed'
EARLIER_R = 'force_controller.force_process.immersion=1.8'


def figures() -> dict[str, str]:
    out: dict[str, str] = {}
    rec = offline(NAME)
    rows = rec.force_control
    for s, key in zip(depth_stretches(rows), ('deep', 'shallow'), strict=True):
        out[f'{key}.depth'] = f'{s.depth:g}'  # [mm]
        out[f'{key}.from'], out[f'{key}.to'] = f'{s.start:.2f}', f'{s.end:.2f}'
        out[f'{key}.instants'] = str(s.instants)
        out[f'{key}.force'] = f'{s.force:.1f}'  # [N]
        out[f'{key}.reference'] = f'{s.reference:.0f}'
        out[f'{key}.override'] = f'{s.override:.4f}'
    override = rows[:, FORCE_CONTROL.index('override')]
    out['end'] = f'{rec.t[-1]:.3f}'  # [s]
    out['samples'] = f'{rec.t.size:,}'.replace(',', ' ')
    out['instants'] = str(len(rows))
    out['override.min'] = f'{override.min():.3f}'
    out['override.mean'] = f'{override.mean():.3f}'
    out['override.max'] = f'{override.max():.3f}'
    for j, t in enumerate(rows[:4, FORCE_CONTROL.index('t')]):  # the first control instants
        out[f'instant.{j}'] = f'{round((t - rec.t[0]) / (rec.t[1] - rec.t[0]))}'  # [sample]
    job = job_for(scenario.load(NAME))  # its length at override 1 (the programmed feed)
    assert isinstance(job, AxisJob)
    dt = job.dt_ns * 1e-9
    out['programmed.end'] = f'{(job.samples - 1) * dt:.3f}'
    out['programmed.path'] = f'{(job.samples - 1 - job.end.settle_samples) * dt:.3f}'
    # the deep cut: override × programmed feed per tooth; the shallow: the override 300 N needs
    plant = scenario.load(NAME).parameters('force_controller')
    deep = out['deep.override']
    per_tooth = (
        float(deep)
        * plant['nominal_feed']
        * 60
        / (plant['force_process.spindle_speed'] * plant['force_process.flutes'])
    )
    out['deep.override3'] = f'{float(deep):.3f}'
    out['deep.chip'] = f'{per_tooth:.3f}'  # [mm]
    kp = plant['force_process.cutting_pressure'] * plant['force_process.immersion']  # N/mm²
    need = plant['reference_force'] / (kp * 2.0 * per_tooth / float(deep))
    out['shallow.needed'] = f'{need:.2f}'
    out['shallow.needed_percent'] = f'{100 * need:.0f}'
    out['shallow.force_n'] = f'{depth_stretches(rows)[1].force:.0f}'
    out['r'] = f'{plant["force_process.immersion"]:.3f}'
    out['r_squared'] = f'{plant["force_process.immersion"] ** 2:.2f}'
    earlier = [s.force for s in depth_stretches(offline(NAME, '', (EARLIER_R,)).force_control)]
    assert math.isclose(*np.round(earlier, 1)), earlier  # the docs say "at both depths"
    out['earlier_r.force'] = f'{earlier[0]:.1f}'
    out['earlier_r.force_n'] = f'{earlier[0]:.0f}'
    return out
