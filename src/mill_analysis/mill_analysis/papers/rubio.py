"""Rubio 2013's metrics and verdicts: the continuous-time cost J_c per scheme. ROS-free."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from mill_analysis.force_record import ForceRecord
from mill_analysis.readings import overall

# The variants of config/rubio.yaml the claims compare: fixed-β holds and the two schemes.
RUBIO_CASES = {'zoh': 'ZOH (β = 0)', 'scheme1': 'scheme 1', 'scheme2': 'scheme 2'}
# The readings the schemes' verdicts rest on, each varied alone from ours (the first): per
# reading, (variant suffix, label). A ZOH variant with the suffix is the ZOH of that reading;
# without one (the index is the schemes' alone) the plain ZOH.
RUBIO_READINGS: tuple[tuple[str, tuple[tuple[str, str], ...]], ...] = (
    (
        'what eq. (13) compares',
        (('', 'error between the samples'), ('_index_sampled', 'error at the samples only')),
    ),
    (
        'the observer polynomial',
        (
            ('', 'z − e^(−T/τ_c)'),
            ('_observer2', '(z − e^(−T/τ_c))²'),
            ('_observer_tau_m', 'z − e^(−T/τ_m)'),
        ),
    ),
)
# The schemes' claims: (variant, claim, holds(J_c of the scheme, J_c of the ZOH)).
RUBIO_SCHEME_CLAIMS = (
    ('scheme1', 'scheme 1 is no worse than ZOH', lambda s, z: s <= z),
    ('scheme2', 'scheme 2 is not better than ZOH', lambda s, z: s >= z),
)


def rubio_reading_cases(records: Mapping[str, ForceRecord]):
    """Per reading combination that was run: (ZOH, scheme 1, scheme 2) J_c."""
    out = {}
    for axis, (_, values) in enumerate(RUBIO_READINGS):
        for suffix, _label in values:
            combo = tuple(suffix if i == axis else '' for i in range(len(RUBIO_READINGS)))
            zoh = records.get('zoh' + suffix) or records.get('zoh')
            schemes = [records.get(v + suffix) for v, _, _ in RUBIO_SCHEME_CLAIMS]
            if zoh is not None and all(schemes):
                out[combo] = (zoh.j_c, *(s.j_c for s in schemes if s))
    return out


def rubio_readings(records: Mapping[str, ForceRecord]) -> list[str]:
    """The schemes' claims under each reading, and the verdict over them all."""
    cases = rubio_reading_cases(records)
    if len(cases) < 2:
        return []
    names = [name for name, _ in RUBIO_READINGS]
    labels = [dict(values) for _, values in RUBIO_READINGS]
    lines = ["the schemes' claims under each reading (J_c against ZOH; ours first):"]
    for combo, (zoh, *schemes) in cases.items():
        reading = '; '.join(f'{names[i]}: {labels[i][s]}' for i, s in enumerate(combo))
        cells = [
            f'{v} {100 * (j / zoh - 1):+.2f} % {"agrees" if holds(j, zoh) else "disagrees"}'
            for (v, _, holds), j in zip(RUBIO_SCHEME_CLAIMS, schemes, strict=True)
        ]
        lines.append(f'  {reading}: ' + ', '.join(cells))
    for i, (_, claim, holds) in enumerate(RUBIO_SCHEME_CLAIMS):
        verdicts = {c: holds(j[1 + i], j[0]) for c, j in cases.items()}
        lines.append(f'claim: {claim}, over the readings: {overall(verdicts, names).lower()}')
    return lines


def rubio_claims(costs: Mapping[float, float], cases: Mapping[str, ForceRecord]) -> str:
    """Rubio 2013's three claims, each with the figures and a computed verdict."""
    zoh = cases['ZOH (β = 0)'].j_c
    negative = {b: c for b, c in costs.items() if b < 0}
    best_b = min(negative, key=lambda b: negative[b])
    s1, s2 = cases['scheme 1'].j_c, cases['scheme 2'].j_c
    rows = [
        (
            'negative β gives lower J_c than ZOH',
            all(c < zoh for c in negative.values()),
            f'{sum(c < zoh for c in negative.values())} of {len(negative)} runs with β < 0 '
            f'below ZOH; best β = {best_b:+.2f}: {100 * (negative[best_b] / zoh - 1):+.2f} %',
        ),
        ('scheme 1 is no worse than ZOH', s1 <= zoh, f'{100 * (s1 / zoh - 1):+.2f} %'),
        ('scheme 2 is not better than ZOH', s2 >= zoh, f'{100 * (s2 / zoh - 1):+.2f} %'),
    ]
    return '\n'.join(
        f'claim: {text}: {"agrees" if ok else "disagrees"} ({detail})' for text, ok, detail in rows
    )


def rubio(records: Mapping[str, ForceRecord]) -> str:
    """J_c of every variant against ZOH, and the paper's three claims with computed verdicts."""
    if 'zoh' not in records:
        return ''
    zoh = records['zoh'].j_c
    lines = [
        'Rubio 2013, peak cutting force held at F_r by the feed (J_c of eq. 14, against ZOH; '
        'the paper gives J_c as a plot only, fig. 10, no numbers):',
        f'{"variant":<22} {"J_c [N² s]":>12} {"vs ZOH [%]":>11} {"active β":>20}',
    ]
    for name, rec in records.items():
        betas = ', '.join(f'{b:g}' for b in dict.fromkeys(rec.beta.tolist()))
        lines.append(f'{name:<22} {rec.j_c:12.6g} {100 * (rec.j_c / zoh - 1):+11.2f} {betas:>20}')
    # Fixed holds: one β over the whole job.
    # The claims' own runs: our readings (a variant of another reading is its own case).
    other = tuple(suffix for _, values in RUBIO_READINGS for suffix, _ in values if suffix)
    ours = {n: r for n, r in records.items() if not n.endswith(other)}
    fixed = {float(rec.beta[0]): rec.j_c for rec in ours.values() if np.ptp(rec.beta) == 0}
    cases = {label: records[name] for name, label in RUBIO_CASES.items() if name in records}
    if len(cases) == len(RUBIO_CASES) and any(b < 0 for b in fixed):
        lines.append(rubio_claims(fixed, cases))
    lines += rubio_readings(records)
    return '\n'.join(lines)
