"""When a node's cores cannot be built from a set of parameter values, in one line. ROS-free.

A node builds its cores (a control law, an observer, ...) from the full set of its parameter
values, at start-up and at every run-time change. Values that pass each parameter's own
check can still make a core that cannot be built: a gain whose square overflows, a design
matrix that is singular, derived gains that are not finite. What such a build raises:

- ValueError: a check of the core, numpy's LinAlgError, scipy's refusals;
- ArithmeticError: OverflowError of float arithmetic, ZeroDivisionError, and numpy's
  FloatingPointError where a build runs under `numpy.errstate(...='raise')`.

mill_common.ros_params refuses such a change with `build_failure`'s line and keeps the
node's previous cores.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from mill_common.registry import Registry

BUILD_ERRORS: tuple[type[Exception], ...] = (ValueError, ArithmeticError)


def build_failure(exc: BaseException) -> str:
    """The reason a build failed, in one line: a check's own message; for anything else
    (OverflowError, LinAlgError, ...) its kind, then its message."""
    text = ' '.join(str(exc).split())
    own = type(exc) is ValueError or type(exc).__module__.startswith('mill_')
    if own and text:
        return text
    return f'{type(exc).__name__}: {text}' if text else type(exc).__name__


def changed_choices(
    registry: Registry[Any], values: Mapping[str, Any], old: Mapping[str, Any]
) -> list[str]:
    """The entries of `registry` other than the one `values` selects whose parameters differ
    between `old` and `values`: their cores are not built by the change, so a node builds a
    candidate of each with the would-be values (one name per class)."""
    selected = registry.get(values[registry.parameter])
    out = []
    for cls in registry.classes():
        if cls is selected:
            continue
        names = [f'{cls.PREFIX}.{spec.name}' for spec in cls.PARAMETERS]
        if any(values.get(n) != old.get(n) for n in names):
            name = registry.name_of(cls)
            assert name is not None  # a class of the registry
            out.append(name)
    return out
