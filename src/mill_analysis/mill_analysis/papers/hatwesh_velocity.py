"""Hatwesh 2013's velocity-step experiment: metrics and verdicts. ROS-free."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from mill_analysis.papers.common import X, verdict
from mill_analysis.record import RunRecord


@dataclass(frozen=True)
class StepMetrics:
    """One step of the velocity reference, judged on the velocity response."""

    time: float  # the step [s]
    size: float  # Δv* [m/s]
    overshoot: float  # beyond the new reference, % of the step
    settling_time: float  # until |v − v*| stays within the band [s] (inf: not in the window)
    iae: float  # ∫|v − v*| dt over the window [µm]


def velocity_steps(rec: RunRecord, start: float, end: float, band: float) -> list[StepMetrics]:
    """Every step of x's reference velocity in [start, end), each judged until the next one.

    band: the settling band as a fraction of the step. v is the drive's true velocity.
    """
    t, v, r = rec.t, rec['true_velocity'][:, X], rec['reference_velocity'][:, X]
    dt = t[1] - t[0]
    edges = np.flatnonzero(np.abs(np.diff(r)) > 0.0) + 1
    edges = edges[(t[edges] >= start) & (t[edges] < end)]
    out = []
    for i, k in enumerate(edges):
        stop = edges[i + 1] if i + 1 < len(edges) else np.searchsorted(t, end)
        size = r[k] - r[k - 1]
        e = (v[k:stop] - r[k:stop]) / size  # in steps; > 0 beyond the new reference
        outside = np.flatnonzero(np.abs(e) > band)
        if outside.size == 0:
            settling = 0.0
        elif outside[-1] == e.size - 1:
            settling = math.inf
        else:
            settling = float(outside[-1] + 1) * dt
        out.append(
            StepMetrics(
                float(t[k]),
                float(size),
                max(0.0, float(np.max(e))) * 100,
                settling,
                float(np.sum(np.abs(v[k:stop] - r[k:stop])) * dt) * 1e6,
            )
        )
    return out


@dataclass(frozen=True)
class PhaseMetrics:
    overshoot: float  # mean over the steps [%]
    settling_time: float  # longest [s]
    iae: float  # mean [µm]
    max_command: float  # largest |u| in the phase [V] (nan: no commands in the record)


def phase_metrics(rec: RunRecord, start: float, end: float, band: float) -> PhaseMetrics:
    steps = velocity_steps(rec, start, end, band)
    u = rec['torque'][(rec.t >= start) & (rec.t < end), X]
    u = u[np.isfinite(u)]  # the runner's record has no commands: offline only
    return PhaseMetrics(
        float(np.mean([s.overshoot for s in steps])),
        max(s.settling_time for s in steps),
        float(np.mean([s.iae for s in steps])),
        float(np.max(np.abs(u))) if u.size else math.nan,
    )


def load_response(rec: RunRecord, start: float, end: float, band: float) -> tuple[float, float]:
    """(largest |v − v*| [mm/s], time until it stays within band [s]) after a load step."""
    t = rec.t
    w = (t >= start) & (t < end)
    e = np.abs(rec['true_velocity'][w, X] - rec['reference_velocity'][w, X])
    outside = np.flatnonzero(e > band)
    dt = t[1] - t[0]
    if outside.size == 0:
        back = 0.0
    elif outside[-1] == e.size - 1:
        back = math.inf
    else:
        back = float(t[w][outside[-1]] - start) + dt
    return float(np.max(e)) * 1e3, back


# config/hatwesh_velocity.yaml: cycles of four 10 mm/s steps, 1 s each; the phases measured
# (cycle 2, 4, 6), the inertia change and the load torque between them.
HV_STEP = 0.010  # [m/s]
HV_BAND = 0.02  # settling band, a fraction of the step (the usual 2 %)
HV_PHASES = {'nominal': (1.1, 2.1), 'after inertia': (3.1, 4.1), 'under load': (5.1, 6.1)}
HV_INERTIA_CHANGE = 2.225
HV_LOAD = (4.225, 4.35)  # the load torque starts; the next step of the reference
HV_CLAIMS = (
    (
        'fig. 3: an incorrect phase margin (25°) gives a large overshoot and a long '
        'settling time (adaptive_pi_pm25 against adaptive_pi, nominal)'
    ),
    (
        'fig. 5: with the desired phase margin the self-tuning PI tracks the set point better '
        'than the machine PI (overshoot, settling and IAE, nominal)'
    ),
    (
        'it copes with the inertia change: its IAE changes by a smaller factor than the '
        "machine PI's (after inertia / nominal)"
    ),
    (
        'it copes with the machining perturbation: under the load torque its IAE changes by '
        "a smaller factor than the machine PI's (under load / after inertia)"
    ),
)


def hv_verdicts(ours: Mapping[str, Mapping[str, PhaseMetrics]]) -> tuple[bool, ...]:
    """Whether each of HV_CLAIMS holds, from the phases of machine_pi, adaptive_pi and
    adaptive_pi_pm25."""
    mach, ada, pm25 = ours['machine_pi'], ours['adaptive_pi'], ours['adaptive_pi_pm25']
    n, a, b = 'nominal', 'after inertia', 'under load'

    def ratio(m: Mapping[str, PhaseMetrics], top: str, bottom: str) -> float:
        return m[top].iae / m[bottom].iae

    return (
        pm25[n].overshoot > ada[n].overshoot and pm25[n].settling_time > ada[n].settling_time,
        ada[n].overshoot <= mach[n].overshoot
        and ada[n].settling_time <= mach[n].settling_time
        and ada[n].iae <= mach[n].iae,
        ratio(ada, a, n) <= ratio(mach, a, n),
        ratio(ada, b, a) <= ratio(mach, b, a),
    )


def hatwesh_velocity(records: Mapping[str, RunRecord]) -> str:
    lines = [
        'Hatwesh 2013, velocity loop of the x drive alone: steps of ±10 mm/s of the velocity '
        'reference, the true velocity judged per phase (mean overshoot, longest settling to '
        f'{100 * HV_BAND:g} % of the step, mean IAE over the four steps of a cycle; the paper '
        'gives figures only, no numbers):',
        f'{"controller":<18} {"phase":<14} {"overshoot [%]":>13} {"settling [ms]":>14} '
        f'{"IAE [µm]":>9} {"max |u| [V]":>12}',
    ]
    ours: dict[str, dict[str, PhaseMetrics]] = {}
    end = max(b for _, b in HV_PHASES.values())
    for name, rec in records.items():
        if rec.t[-1] < end - 2 * (rec.t[1] - rec.t[0]):
            lines.append(f'{name:<18} run ends before the last phase: no paper metrics')
            continue
        ours[name] = {k: phase_metrics(rec, a, b, HV_BAND) for k, (a, b) in HV_PHASES.items()}
        for phase, m in ours[name].items():
            lines.append(
                f'{name:<18} {phase:<14} {m.overshoot:13.2f} {m.settling_time * 1e3:14.2f} '
                f'{m.iae:9.3f} {m.max_command:12.2f}'.replace('nan', 'n/a')
            )
    span = (HV_LOAD[1] - HV_LOAD[0]) * 1e3
    lines.append(
        f'load torque from t = {HV_LOAD[0]:g} s at 10 mm/s, until the next step {span:g} ms '
        f'later: largest |v − v*|, and when it is back within {HV_BAND * HV_STEP * 1e3:g} mm/s:'
    )
    for name, rec in records.items():
        if name in ours:
            drop, back = load_response(rec, *HV_LOAD, HV_BAND * HV_STEP)
            when = f'not within {span:g} ms'
            if math.isfinite(back):
                when = f'after {back * 1e3:.2f} ms'
            lines.append(f'{name:<18} {drop:8.3f} mm/s, {when}')
    if {'machine_pi', 'adaptive_pi', 'adaptive_pi_pm25'} <= ours.keys():
        mach, ada, pm25 = ours['machine_pi'], ours['adaptive_pi'], ours['adaptive_pi_pm25']
        n, a, b = 'nominal', 'after inertia', 'under load'

        def ratio(m: dict[str, PhaseMetrics], top: str, bottom: str) -> float:
            return m[top].iae / m[bottom].iae

        verdicts = hv_verdicts(ours)
        details = (
            f'overshoot {pm25[n].overshoot:.1f} % against {ada[n].overshoot:.1f} %, settling '
            f'{pm25[n].settling_time * 1e3:.2f} ms against {ada[n].settling_time * 1e3:.2f} ms',
            f'overshoot {ada[n].overshoot:.2f} % against {mach[n].overshoot:.2f} %, settling '
            f'{ada[n].settling_time * 1e3:.2f} against {mach[n].settling_time * 1e3:.2f} ms, '
            f'IAE {ada[n].iae:.3f} against {mach[n].iae:.3f} µm',
            f'IAE ×{ratio(ada, a, n):.3f} against ×{ratio(mach, a, n):.3f}',
            f'IAE ×{ratio(ada, b, a):.3f} against ×{ratio(mach, b, a):.3f}; overshoot '
            f'{ada[a].overshoot:.1f} → {ada[b].overshoot:.1f} % against '
            f'{mach[a].overshoot:.2f} → {mach[b].overshoot:.2f} %',
        )
        for text, holds, detail in zip(HV_CLAIMS, verdicts, details, strict=True):
            lines.append(f'claim "{text}": {verdict(holds)} ({detail})')
    return '\n'.join(lines)
