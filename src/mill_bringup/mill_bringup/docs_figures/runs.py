"""The offline runs behind the docs' figures, each run once per process (cached)."""

from __future__ import annotations

import functools
import math
from typing import Any

from mill_bringup import scenario
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.registry import job_for


@functools.cache
def offline(name: str, variant: str = '', overrides: tuple[str, ...] = ()) -> Any:
    """`offline_sim NAME --variant VARIANT -p OVERRIDE ...`'s record (variant '' = none)."""
    scen = scenario.load(name)
    run = scen.variant(variant) if variant else scen
    for text in overrides:
        run.add_override(text)
    return simulate(job_for(run))


def law_values(params: dict[str, Any], prefix: str) -> dict[str, Any]:
    """A node's parameters of one law or observer (`prefix.NAME`), by NAME."""
    return {
        k.removeprefix(prefix + '.'): v for k, v in params.items() if k.startswith(prefix + '.')
    }


def sig(x: float, digits: int = 4) -> str:
    """x to `digits` significant digits, never in exponent form above 1 (1257, not 1.257e+03)."""
    if not math.isfinite(x):
        return 'inf' if x > 0 else 'nan'
    text = f'{x:#.{digits}g}'.rstrip('.')  # '#': keep trailing zeros (0.1400)
    if 'e' in text and abs(x) >= 1:
        text = f'{x:.0f}'
    return '−' + text[1:] if text.startswith('-') else text  # the docs' minus sign
