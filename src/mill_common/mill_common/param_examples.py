"""Hypothesis strategies of parameter values, from a ParamSpec alone: for the property tests
of every package, which iterate their registries' declared parameters instead of listing
them by hand.

Each strategy mixes values the spec's check accepts, its edges (bounds, 0, ±1e-300,
±1e300, the default scaled by powers of ten) and values it refuses (NaN, ±inf, negative,
wrong types), so that a test sees both what a node must take and what it must refuse.
Needs hypothesis (a test dependency): import this module from tests only.
"""

from __future__ import annotations

import math
from typing import Any

from mill_common.parameters import OneOf, ParamSpec, value_type

EDGES = (0.0, 1e-300, -1e-300, 1e-9, 1.0, -1.0, 1e9, 1e300, -1e300, math.inf, -math.inf, math.nan)
WRONG = ('x', True, None)


def number_values(spec: ParamSpec) -> Any:
    """Floats around the spec's default and bounds, and the edges."""
    import hypothesis.strategies as st

    default = spec.default if isinstance(spec.default, int | float) else 1.0
    bounds = getattr(spec.check, 'bounds', None) or ()
    near = [b for b in bounds if math.isfinite(b)] + [float(default)]
    scaled = st.builds(
        lambda base, exp, sign: sign * (abs(base) or 1.0) * 10.0**exp,
        st.sampled_from(near),
        st.integers(-300, 300),
        st.sampled_from((1.0, -1.0)),
    )
    return st.one_of(
        st.sampled_from(EDGES + tuple(near)),
        scaled,
        st.floats(allow_nan=True, allow_infinity=True),
    )


def integer_values(spec: ParamSpec) -> Any:
    import hypothesis.strategies as st

    bounds = getattr(spec.check, 'bounds', None) or (0, 10)
    lo = int(bounds[0]) if math.isfinite(bounds[0]) else -10
    hi = int(bounds[1]) if math.isfinite(bounds[1]) else lo + 10
    return st.one_of(
        st.integers(lo, min(hi, lo + 8)),  # small, accepted counts: the cores are built
        st.sampled_from((lo - 1, hi, hi + 1, 10**9, 2**63 - 1, -(2**31))),
    )


def values(spec: ParamSpec) -> Any:
    """A strategy of values to set `spec` to: accepted ones, edges and refused ones."""
    import hypothesis.strategies as st

    kind = value_type(spec)
    wrong = st.sampled_from(WRONG)
    if kind == 'bool':
        return st.one_of(st.booleans(), st.sampled_from(('maybe', 1)))
    if kind == 'integer':
        return st.one_of(integer_values(spec), wrong)
    if kind == 'double':
        return st.one_of(number_values(spec), wrong)
    if kind == 'string':
        choices = spec.check.choices if isinstance(spec.check, OneOf) else (spec.default,)
        return st.one_of(st.sampled_from(choices), st.text(max_size=4))
    if kind == 'double_array':
        default = list(spec.default) or [1.0]
        entry = number_values(ParamSpec(spec.name, default[0], ''))
        one_changed = st.builds(
            lambda i, v: [v if j == i % len(default) else x for j, x in enumerate(default)],
            st.integers(0, len(default) - 1),
            entry,
        )
        return st.one_of(one_changed, st.lists(entry, max_size=len(default) + 2))
    if kind == 'integer_array':
        return st.lists(st.integers(-2, 8), max_size=4)
    return st.lists(st.text(max_size=4), max_size=3)
