"""Hatwesh 2013's metrics and verdicts: the two moves around the inertia step. ROS-free."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from mill_analysis.papers.common import X, verdict
from mill_analysis.record import RunRecord


@dataclass(frozen=True)
class MoveMetrics:
    overshoot: float  # beyond the target, % of the move length
    settling_time: float  # after the end of the move, until |e| stays in the band [s] (inf: never)
    iae: float  # ∫|e| dt over the move and its settling window [mm·s]


def move_metrics(rec: RunRecord, start: float, end: float, settle: float, band: float):
    """Metrics of one rest-to-rest move of x from `start` to `end` [s], settling window after.

    band: the settling band as a fraction of the move length.
    """
    t, y, r = rec.t, rec['position'][:, X], rec['reference'][:, X]
    move = (t >= start) & (t < end + settle)
    length = r[t < end + settle][-1] - r[t >= start][0]
    e = r - y
    direction = math.copysign(1.0, length)
    target = r[move][-1]
    overshoot = max(0.0, float(np.max((y[move] - target) * direction))) / abs(length) * 100
    after = (t >= end) & (t < end + settle)
    outside = np.nonzero(np.abs(e[after]) > band * abs(length))[0]
    if outside.size == 0:
        settling = 0.0
    elif outside[-1] == np.count_nonzero(after) - 1:
        settling = math.inf  # still outside the band at the end of the window
    else:
        settling = float(t[after][outside[-1]] - end) + (t[1] - t[0])
    iae = float(np.sum(np.abs(e[move])) * (t[1] - t[0])) * 1e3
    return MoveMetrics(overshoot, settling, iae)


# The two identical moves of the Hatwesh scenario (config/hatwesh.yaml): before and after
# the inertia step. Times [s]: move start, move end, and the settling window after it.
HATWESH_MOVES = {'before': (0.0, 0.5, 0.5), 'after': (1.5, 2.0, 0.5)}
HATWESH_BAND = 1e-4


def hatwesh(records: Mapping[str, RunRecord]) -> str:
    lines = [
        'Hatwesh 2013, x axis velocity loop, the same move before and after a load-inertia '
        'step (settling band 0.01 % of the move, 1 µm; the paper gives figures only, no '
        'numbers, and judges the velocity response: see hatwesh_velocity):',
        f'{"controller":<16} {"move":<7} {"overshoot [%]":>14} {"settling [ms]":>14} '
        f'{"IAE [mm s]":>11}',
    ]
    ratios, after = {}, {}
    last_end = max(end + settle for _, end, settle in HATWESH_MOVES.values())
    for name, rec in records.items():
        if rec.t[-1] < last_end - (rec.t[1] - rec.t[0]) * 1.5:
            lines.append(f'{name:<16} run ends before the second move: no paper metrics')
            continue
        m = {k: move_metrics(rec, *v, HATWESH_BAND) for k, v in HATWESH_MOVES.items()}
        for k, v in m.items():
            lines.append(
                f'{name:<16} {k:<7} {v.overshoot:14.3f} {v.settling_time * 1e3:14.2f} {v.iae:11.6f}'
            )
        ratios[name] = m['after'].iae / m['before'].iae
        after[name] = m['after'].iae
    if {'machine_pi', 'adaptive_pi'} <= ratios.keys():
        lines.append(
            'IAE after / before the inertia step: '
            + ', '.join(f'{k} {v:.3f}' for k, v in ratios.items())
        )
        holds = ratios['adaptive_pi'] <= ratios['machine_pi']
        lines.append(
            'claim "the adaptive PI keeps its performance after the inertia change, '
            'where the fixed machine PI loses some": ' + verdict(holds)
        )
        better = after['adaptive_pi'] <= after['machine_pi']
        lines.append(
            "and after the change the adaptive PI's IAE is "
            + ('lower' if better else 'still HIGHER')
            + " than the machine PI's"
        )
    return '\n'.join(lines)
