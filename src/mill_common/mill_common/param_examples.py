"""Values to try a parameter with, from its ParamSpec alone: for the property tests of every
package, which iterate their registries' declared parameters instead of listing them by
hand (they draw from these with hypothesis). ROS-free.

The values mix what the spec's check accepts, its edges (bounds, 0, ±1e-300, ±1e300, the
default scaled by powers of ten) and what it refuses (NaN, ±inf, out of range, wrong
types), so that a test sees both what a node must take and what it must refuse.
"""

from __future__ import annotations

import math
from typing import Any

from mill_common.parameters import OneOf, ParamSpec, value_type

EDGES = (0.0, 1e-300, -1e-300, 1e-9, 1.0, -1.0, 1e9, 1e300, -1e300, math.inf, -math.inf, math.nan)
WRONG = ('x', True, None)
POWERS = (-300, -100, -30, -12, -6, -3, -2, -1, 1, 2, 3, 6, 12, 30, 100, 300)


def numbers(spec: ParamSpec) -> tuple[float, ...]:
    """The edges, the finite bounds of the check and the default, each also scaled by
    powers of ten, of both signs."""
    default = spec.default if isinstance(spec.default, int | float) else 1.0
    bounds = getattr(spec.check, 'bounds', None) or ()
    near = [float(b) for b in bounds if math.isfinite(b)] + [float(default)]
    scaled = [s * (abs(b) or 1.0) * 10.0**p for b in near for p in POWERS for s in (1.0, -1.0)]
    return tuple(dict.fromkeys([*EDGES, *near, *scaled]))


def integers(spec: ParamSpec) -> tuple[int, ...]:
    """The small counts from the check's lower bound, its upper bound and beyond."""
    bounds = getattr(spec.check, 'bounds', None) or (0, 10)
    lo = int(bounds[0]) if math.isfinite(bounds[0]) else -10
    hi = int(bounds[1]) if math.isfinite(bounds[1]) else lo + 10
    small = range(lo, min(hi, lo + 8) + 1)
    return tuple(dict.fromkeys([*small, lo - 1, hi, hi + 1, 10**9, 2**63 - 1, -(2**31)]))


def examples(spec: ParamSpec) -> tuple[Any, ...]:
    """Values to set `spec` to: accepted ones, edges and refused ones."""
    kind = value_type(spec)
    if kind == 'bool':
        return (True, False, 'maybe', 1)
    if kind == 'integer':
        return integers(spec) + WRONG
    if kind == 'double':
        return numbers(spec) + WRONG
    if kind == 'string':
        choices = spec.check.choices if isinstance(spec.check, OneOf) else (spec.default,)
        return (*choices, '', 'bogus', 1.0)
    if kind == 'double_array':
        default = list(spec.default) or [1.0]
        entries = numbers(ParamSpec(spec.name, default[0], ''))
        changed = [
            [v if j == i else x for j, x in enumerate(default)]
            for i in range(len(default))
            for v in entries[:: max(1, len(entries) // 16)]
        ]
        return (*changed, [], default[:-1], [*default, default[-1]], [1.0] * 100, ['x'])
    if kind == 'integer_array':
        return ([], [0], [0, 0], [-1], [10**6])
    return ([], ['x'], [''], [1.0])
