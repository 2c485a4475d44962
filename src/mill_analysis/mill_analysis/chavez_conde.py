"""Chávez-Conde's claims, computed from the runs of config/chavez_conde.yaml. ROS-free.

The paper publishes plots only (figs. 5-10, lost in the text) and three claims (section 6):
the GPI law performs well but needs more robustness to reduce its tracking error; the
sliding-mode GPI "reduces and maintains" the error; and the discontinuity brings a high
frequency that should be reduced. Each pair gpi* / sliding_gpi* is judged on the second.
The paper leaves three settings open that change that verdict (READINGS: the sample period,
the unit of c_t, what the plant does when the carriage reverses); the report gives it under
every combination and says "depends on …" where they differ. The project's reading is the
pair PAPER (Fig. 2 force, continuous laws at 0.1 ms, c_t translational, reversal `through`,
rigid x axis, no torque limit). A run whose axis tripped is reported as the time and error
of its trip, not as tracking figures.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence

import numpy as np
from mill_common.signals import AXES

from mill_analysis.events import TRIP
from mill_analysis.metrics import peak, rms
from mill_analysis.readings import overall
from mill_analysis.record import RunRecord

X = 0
PAPER = ('gpi', 'sliding_gpi')
# What each variant suffix changes against the paper's setting (config/chavez_conde.yaml).
SETTINGS = {
    '_zoh': 'laws redesigned for a 1 ms zero-order hold',
    '_regenerative': "chip from the tool's own path instead of the Fig. 2 force",
    '_flexible': 'flexible axis of eq. (4)-(6)',
    '_limited': 'a ±5 N m torque limit the paper does not have',
    '_1ms': "sampled at 1 ms, the paper's fixed step",
    '_ct_literal': 'c_t read literally (c_b + c_t/a²)',
    '_stop': "the plant's default reversal (stop)",
}
# The readings the sliding-law verdict rests on: per reading, (variant suffix, label) with
# the project's first. Every combination is a variant pair of config/chavez_conde.yaml.
READINGS: tuple[tuple[str, tuple[tuple[str, str], ...]], ...] = (
    ('the sample period', (('', '0.1 ms'), ('_1ms', '1 ms (the paper)'))),
    ('c_t', (('', 'translational'), ('_ct_literal', 'literal, c_t/a²'))),
    ('the friction reversal', (('', 'through'), ('_stop', 'stop (default)'))),
)
# "A high frequency from the discontinuity": the sliding law's RMS torque change per sample
# at least this many times the GPI law's.
CHATTER_FACTOR = 100.0


def tracking_metrics(rec: RunRecord) -> tuple[float, float]:
    """max |e| and RMS e of the x axis over the whole run [mm]."""
    e = rec.tracking_error[:, X]
    return peak(e) * 1e3, rms(e) * 1e3


def trip(rec: RunRecord) -> tuple[float, float] | None:
    """When the x axis tripped on its following error and |e| there [s, mm]; None: never.
    After a trip the axis is braked: its figures are not the law's tracking."""
    for event in rec.events:
        if event.kind == TRIP and event.axis == AXES[X] and math.isfinite(event.time):
            k = min(int(np.searchsorted(rec.t, event.time - 1e-12)), len(rec.t) - 1)
            return event.time, abs(float(rec.tracking_error[k, X])) * 1e3
    return None


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


def reduces(
    gpi: tuple[float, float],
    sliding: tuple[float, float],
    gpi_trip: tuple[float, float] | None = None,
    sliding_trip: tuple[float, float] | None = None,
) -> str:
    """The verdict on "the sliding-mode GPI reduces the tracking error": (max, RMS) each;
    where a law tripped, the one that tripped later (or not at all) is the better."""
    if gpi_trip or sliding_trip:
        return _verdict((sliding_trip or (math.inf,))[0] > (gpi_trip or (math.inf,))[0])
    return _verdict(sliding[1] < gpi[1] and sliding[0] < gpi[0])


def variant_of(law: str, suffixes: Sequence[str]) -> str:
    return law + ''.join(suffixes)


def reading_verdicts(
    ours: Mapping[str, tuple[float, float]], trips: Mapping[str, tuple[float, float] | None]
) -> dict[tuple[str, ...], bool]:
    """The sliding-law verdict under every combination of READINGS that was run."""
    out = {}
    for combo in itertools.product(*(dict(values) for _, values in READINGS)):
        gpi, sliding = variant_of('gpi', combo), variant_of('sliding_gpi', combo)
        if gpi in ours and sliding in ours:
            v = reduces(ours[gpi], ours[sliding], trips.get(gpi), trips.get(sliding))
            out[combo] = v == 'agrees'
    return out


def describe(metrics: tuple[float, float], tripped: tuple[float, float] | None) -> str:
    if tripped:
        return f'braked at {tripped[0]:.4g} s (|e| {tripped[1]:.4g} mm)'
    return f'{metrics[0]:.4g} / {metrics[1]:.4g}'


def readings_table(
    ours: Mapping[str, tuple[float, float]], trips: Mapping[str, tuple[float, float] | None]
) -> list[str]:
    """The sliding-law verdict under each reading: one row per combination run."""
    verdicts = reading_verdicts(ours, trips)
    if len(verdicts) < 2:
        return []
    names = [name for name, _ in READINGS]
    labels = [dict(values) for _, values in READINGS]
    lines = [
        'claim "the sliding-mode GPI reduces the tracking error" under each reading '
        "(max / RMS e [mm]; the project's reading first):",
        '  '.join(f'{n:<22}' for n in names) + f'  {"GPI":>22}  {"sliding-mode GPI":>22}  verdict',
    ]
    for combo, holds in verdicts.items():
        gpi, sliding = variant_of('gpi', combo), variant_of('sliding_gpi', combo)
        lines.append(
            '  '.join(f'{labels[i][s]:<22}' for i, s in enumerate(combo))
            + f'  {describe(ours[gpi], trips.get(gpi)):>22}'
            + f'  {describe(ours[sliding], trips.get(sliding)):>22}  '
            + _verdict(holds)
        )
    lines.append(
        'claim "the sliding-mode GPI reduces the tracking error", rigid axis, sample period '
        'and readings as above: ' + overall(verdicts, names)
    )
    return lines


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
    trips: dict[str, tuple[float, float] | None] = {}
    for name, rec in records.items():
        peak, rms = ours[name] = tracking_metrics(rec)
        top, at_top, chatter = torque[name] = torque_metrics(rec)
        if tripped := trips.setdefault(name, trip(rec)):
            lines.append(
                f'{name:<26} braked: following-error trip at t = {tripped[0]:.4f} s, '
                f'|e| = {tripped[1]:.4f} mm (no tracking figures) {top:16.4f} {at_top:11.2f} '
                f'{chatter:15.6f}'
            )
            continue
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
        if trips[gpi] or trips[sliding]:
            figures = (
                f'GPI {describe(ours[gpi], trips[gpi])}, sliding-mode GPI '
                f'{describe(ours[sliding], trips[sliding])}'
            )
        else:
            figures = f'RMS e x{rs / rg:.2f}, max |e| x{ps / pg:.2f}'
        lines.append(
            f'claim "the sliding-mode GPI reduces the tracking error" ({sliding} vs {gpi}, '
            f'{setting}): {figures} — '
            + reduces(ours[gpi], ours[sliding], trips[gpi], trips[sliding])
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
            "verdict in the project's reading (gpi vs sliding_gpi: the Fig. 2 force, continuous "
            'laws at 0.1 ms, c_t translational, reversal through, rigid x axis, no torque '
            'limit): ' + reduces(ours[PAPER[0]], ours[PAPER[1]])
        )
    lines += readings_table(ours, trips)
    return '\n'.join(lines)
