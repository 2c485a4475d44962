"""Chávez-Conde's claims, computed from the runs of config/chavez_conde.yaml. ROS-free.

The paper publishes plots only (figs. 5-10, lost in the text) and three claims (section 6):
the GPI law performs well but needs more robustness to reduce its tracking error; the
sliding-mode GPI "reduces and maintains" the error; and the discontinuity brings a high
frequency that should be reduced. Each pair gpi* / sliding_gpi* is judged on the second;
the paper's own setting is the pair PAPER (Fig. 2 force, continuous laws, rigid x axis, no
torque limit); the others say what changes the verdict.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from mill_analysis.metrics import peak, rms
from mill_analysis.record import RunRecord

X = 0
PAPER = ('gpi', 'sliding_gpi')
# What each variant suffix changes against the paper's setting (config/chavez_conde.yaml).
SETTINGS = {
    '_zoh': 'laws redesigned for a 1 ms zero-order hold',
    '_regenerative': "chip from the tool's own path instead of the Fig. 2 force",
    '_flexible': 'flexible axis of eq. (4)-(6)',
    '_limited': 'a ±5 N m torque limit the paper does not have',
}
# "A high frequency from the discontinuity": the sliding law's RMS torque change per sample
# at least this many times the GPI law's.
CHATTER_FACTOR = 100.0


def tracking_metrics(rec: RunRecord) -> tuple[float, float]:
    """max |e| and RMS e of the x axis over the whole run [mm]."""
    e = rec.tracking_error[:, X]
    return peak(e) * 1e3, rms(e) * 1e3


def torque_metrics(rec: RunRecord) -> tuple[float, float, float]:
    """max |τ| [N m], share of samples at it [%], RMS τ change per sample [N m] (nan: the
    runner's record holds no commands)."""
    u = rec['torque'][:, X]
    u = u[np.isfinite(u)]
    if not u.size:
        return math.nan, math.nan, math.nan
    top = float(np.max(np.abs(u)))
    at_top = float(np.mean(np.abs(u) >= top * (1 - 1e-9))) * 100
    return top, at_top, float(np.sqrt(np.mean(np.diff(u) ** 2)))


def _verdict(holds: bool) -> str:
    return 'agrees' if holds else 'DISAGREES'


def reduces(gpi: tuple[float, float], sliding: tuple[float, float]) -> str:
    """The verdict on "the sliding-mode GPI reduces the tracking error": (max, RMS) each."""
    return _verdict(sliding[1] < gpi[1] and sliding[0] < gpi[0])


def chatters(ratio: float) -> str:
    """The verdict on "the discontinuity brings a high frequency" (RMS Δτ ratio)."""
    return _verdict(ratio >= CHATTER_FACTOR)


def chavez_conde(records: Mapping[str, RunRecord]) -> str:
    lines = [
        'Chávez-Conde, x axis, Bézier 0 -> 10 mm in 3 s with friction and cutting force '
        '(torque: share of samples at the largest |tau|, RMS change per sample):',
        f'{"controller":<26} {"max |e| [mm]":>13} {"RMS e [mm]":>11} {"max |tau| [N m]":>16} '
        f'{"at max [%]":>11} {"RMS dtau [N m]":>15}',
    ]
    ours, torque = {}, {}
    for name, rec in records.items():
        peak, rms = ours[name] = tracking_metrics(rec)
        top, at_top, chatter = torque[name] = torque_metrics(rec)
        lines.append(
            f'{name:<26} {peak:13.6f} {rms:11.6f} {top:16.4f} {at_top:11.2f} {chatter:15.6f}'
        )
    for gpi in ours:
        sliding = gpi.replace('gpi', 'sliding_gpi', 1)
        if not gpi.startswith('gpi') or sliding not in ours:
            continue
        changed = [text for suffix, text in SETTINGS.items() if suffix in gpi]
        setting = "the paper's setting" if (gpi, sliding) == PAPER else ', '.join(changed)
        (pg, rg), (ps, rs) = ours[gpi], ours[sliding]
        lines.append(
            f'claim "the sliding-mode GPI reduces the tracking error" ({sliding} vs {gpi}, '
            f'{setting}): RMS e x{rs / rg:.2f}, max |e| x{ps / pg:.2f} — '
            + reduces(ours[gpi], ours[sliding])
        )
    if set(PAPER) <= ours.keys():
        ratio = torque[PAPER[1]][2] / torque[PAPER[0]][2]
        if math.isfinite(ratio):
            lines.append(
                'claim "the discontinuity brings a high frequency" (RMS dtau per sample, '
                f'sliding_gpi / gpi, holds if >= {CHATTER_FACTOR:g}): x{ratio:.0f} — '
                + chatters(ratio)
            )
        lines.append(
            "verdict in the paper's setting (gpi vs sliding_gpi: the Fig. 2 force, continuous "
            'laws, rigid x axis, no torque limit): ' + reduces(ours[PAPER[0]], ours[PAPER[1]])
        )
    return '\n'.join(lines)
