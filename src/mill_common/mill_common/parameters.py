"""Parameter specifications, ROS-free.

An algorithm lists its parameters as ParamSpec entries (name, default,
description, check). Nodes turn them into ROS parameters with descriptions;
the same checks reject bad values at start-up and at run time, so an invalid
value is always refused with a reason and never half-applied.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol

Check = Callable[[Any], 'str | None']


def no_check(_value: Any) -> str | None:
    return None


@dataclass(frozen=True)
class ParamSpec:
    """One parameter: name (without any prefix), default, description, and a check.

    check returns None when the value is acceptable, otherwise the reason it is not.
    """

    name: str
    default: Any
    description: str
    check: Check = no_check
    read_only: bool = False


class Plugin(Protocol):
    """An algorithm class with parameters: its namespace (PREFIX) and its parameters."""

    PREFIX: ClassVar[str]
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]]


class ParameterError(ValueError):
    """A parameter value was refused; str() is a one-line message naming it."""

    def __init__(self, name: str, value: Any, reason: str) -> None:
        super().__init__(f'invalid parameter {name}={value!r}: {reason}')
        self.name = name
        self.value = value
        self.reason = reason


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def number(value: Any) -> str | None:
    if not _is_number(value) or not math.isfinite(value):
        return 'must be a finite number'
    return None


def positive(value: Any) -> str | None:
    return number(value) or (None if value > 0 else 'must be > 0')


def non_negative(value: Any) -> str | None:
    return number(value) or (None if value >= 0 else 'must be >= 0')


def positive_or_inf(value: Any) -> str | None:
    if _is_number(value) and value == math.inf:
        return None
    return positive(value)


def in_range(lo: float, hi: float) -> Check:
    def check(value: Any) -> str | None:
        return number(value) or (None if lo <= value <= hi else f'must be in [{lo}, {hi}]')

    return check


def positive_int(value: Any) -> str | None:
    if not isinstance(value, int) or isinstance(value, bool) or value < 1:
        return 'must be a whole number >= 1'
    return None


def non_negative_int(value: Any) -> str | None:
    if not isinstance(value, int) or isinstance(value, bool) or value < 0:
        return 'must be a whole number >= 0'
    return None


def one_of(*choices: str) -> Check:
    def check(value: Any) -> str | None:
        if value in choices:
            return None
        return f'must be one of: {", ".join(choices)}'

    return check


def boolean(value: Any) -> str | None:
    return None if isinstance(value, bool) else 'must be true or false'


def text(value: Any) -> str | None:
    return None if isinstance(value, str) else 'must be a string'


def number_list(length: int | None = None, each: Check = number) -> Check:
    """A list of numbers, optionally of a fixed length, each passing `each`."""

    def check(value: Any) -> str | None:
        if not isinstance(value, list | tuple):
            return 'must be a list of numbers'
        if length is not None and len(value) != length:
            return f'must have {length} entries, got {len(value)}'
        for i, item in enumerate(value):
            reason = each(item)
            if reason:
                return f'entry {i} {reason}'
        return None

    return check


def coerce(spec: ParamSpec, value: Any) -> Any:
    """Accept an integer where a float is expected (YAML writes 12 for 12.0)."""
    if isinstance(spec.default, float) and _is_number(value):
        return float(value)
    is_float_list = isinstance(spec.default, list | tuple) and bool(spec.default)
    if is_float_list and isinstance(spec.default[0], float) and isinstance(value, list | tuple):
        return [float(v) if _is_number(v) else v for v in value]
    return value


def validate(spec: ParamSpec, value: Any, full_name: str | None = None) -> Any:
    """Return the coerced value, or raise ParameterError with the reason."""
    value = coerce(spec, value)
    reason = spec.check(value)
    if reason:
        raise ParameterError(full_name or spec.name, value, reason)
    return value


def validate_all(
    specs: Sequence[ParamSpec], values: Mapping[str, Any], prefix: str = ''
) -> dict[str, Any]:
    """Validate a mapping name -> value (names without prefix); missing names take defaults."""
    out: dict[str, Any] = {}
    for spec in specs:
        raw = values.get(spec.name, spec.default)
        out[spec.name] = validate(spec, raw, prefix + spec.name)
    return out


def axis_node_specs() -> list[tuple[str, ParamSpec]]:
    """Parameters every per-axis node (controller, observer) has."""
    from mill_common.signals import AXES

    return [
        ('axis', ParamSpec('axis', 'x', 'machine axis this node serves', one_of(*AXES), True)),
        (
            'input_gain',
            ParamSpec(
                'input_gain',
                0.0,
                'b of the nominal model x" = b tau + xi [m/s^2 per N m]; '
                '0 = 1/(a m_e) from Beltrán 2013 Table 1 for this axis',
                lambda v: number(v) or (None if v >= 0 else 'must be >= 0 (0 = nominal)'),
            ),
        ),
        (
            'sample_period',
            ParamSpec('sample_period', 0.001, 'sample period T [s]', in_range(1e-6, 1.0), True),
        ),
        (
            'timing',
            ParamSpec(
                'timing',
                'lockstep',
                'lockstep: inputs joined by their exact stamps on the sample grid (the plant is '
                'the clock); realtime: act on the newest state, the reference interpolated at '
                'its stamp, nothing stale queued',
                one_of('lockstep', 'realtime'),
                True,
            ),
        ),
        (
            'plant_node',
            ParamSpec(
                'plant_node',
                'plant',
                'the node whose states this node accepts (header.frame_id); states from any '
                'other node are dropped and reported',
                text,
                True,
            ),
        ),
        (
            'input_warn_time',
            ParamSpec(
                'input_warn_time',
                1.0,
                'an input silent this long (after its first message) is reported as WARN [s]',
                in_range(0.01, 3600.0),
            ),
        ),
        (
            'input_timeout',
            ParamSpec(
                'input_timeout',
                10.0,
                'an input silent this long is an ERROR; in lockstep the node then ends with a '
                'message naming it [s]',
                in_range(0.01, 3600.0),
            ),
        ),
        (
            'command_delay',
            ParamSpec(
                'command_delay',
                0,
                'samples N between the measurement a command is computed from and the period it '
                'acts in (realtime: 1); the observer predicts with the commands that really act '
                'and estimates the state N samples ahead, the controller aims at the reference '
                'N samples ahead',
                non_negative_int,
                True,
            ),
        ),
    ]


def algorithm_specs(classes: Iterable[type[Plugin]]) -> list[tuple[str, ParamSpec]]:
    """Parameters of registered algorithm classes under their PREFIX, each full name once."""
    specs: dict[str, ParamSpec] = {}
    for cls in classes:
        for spec in cls.PARAMETERS:
            specs.setdefault(f'{cls.PREFIX}.{spec.name}', spec)
    return list(specs.items())


def algorithm_values(cls: type[Plugin], values: Mapping[str, Any]) -> dict[str, Any]:
    """An algorithm's own values (names without prefix) out of a node's values."""
    return {s.name: values[f'{cls.PREFIX}.{s.name}'] for s in cls.PARAMETERS}
