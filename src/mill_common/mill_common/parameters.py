"""Parameter specifications, ROS-free.

An algorithm lists its parameters as ParamSpec entries (name, default,
description, check). Nodes turn them into ROS parameters with descriptions;
the same checks reject bad values at start-up and at run time, so an invalid
value is always refused with a reason and never half-applied.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

if TYPE_CHECKING:
    pass

Check = Callable[[Any], 'str | None']


def no_check(_value: Any) -> str | None:
    return None


class Constraint:
    """A check that also describes itself, for the parameter descriptor a node declares.

    Calling it checks a value (None, or the reason the value is refused). `text` is the
    constraint in one line (ROS `additional_constraints`); `bounds` the closed interval
    [lo, hi] every accepted number lies in (ROS `floating_point_range` / `integer_range`),
    None where the check is no interval; `low_open` says that lo itself is refused (as
    `> 0` refuses 0: a ROS range is closed, so the descriptor shows [0, ...] and the text
    says `> 0`). `value_type` names the type of a list whose default is empty.
    """

    text: str = ''
    bounds: tuple[float, float] | None = None
    low_open: bool = False
    value_type: str | None = None

    def __call__(self, value: Any) -> str | None:
        raise NotImplementedError

    def __repr__(self) -> str:
        return f'<{type(self).__name__} {self.text}>'


@dataclass(frozen=True)
class ParamSpec:
    """One parameter: name (without any prefix), default, description, and a check.

    check returns None when the value is acceptable, otherwise the reason it is not. A
    `Constraint` also gives the node's parameter descriptor its range and constraint text;
    the type comes from the default (see `value_type`).
    """

    name: str
    default: Any
    description: str
    check: Check = no_check
    read_only: bool = field(default=False, kw_only=True)
    unit: str = field(default='', kw_only=True)  # also in the description, as `[unit]`


class Plugin(Protocol):
    """An algorithm class with parameters: its namespace (PREFIX) and its parameters."""

    PREFIX: ClassVar[str]
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]]


# The most of a value a one-line message shows (a parameter file may hold a list of a
# million numbers: its refusal stays one short line).
SHOWN_CHARS = 200


def shown(value: Any) -> str:
    """repr(value), cut to SHOWN_CHARS with what was left out said."""
    text = repr(value)
    if len(text) <= SHOWN_CHARS:
        return text
    return f'{text[:SHOWN_CHARS]}... ({len(text) - SHOWN_CHARS} more characters)'


class ParameterError(ValueError):
    """A parameter value was refused; str() is a one-line message naming it."""

    def __init__(self, name: str, value: Any, reason: str) -> None:
        super().__init__(f'invalid parameter {name}={shown(value)}: {reason}')
        self.name = name
        self.value = value
        self.reason = reason


class UnknownParameterError(ParameterError):
    """Parameters were given that nothing declares; str() names them in one line."""

    def __init__(self, given: Mapping[str, Any], known: Iterable[str], owner: str) -> None:
        ValueError.__init__(self, unknown_parameters_message(given, known, owner))
        self.names = sorted(given)
        self.name = self.names[0]
        self.value = given[self.name]
        self.reason = 'unknown'


def unknown_parameters_message(
    given: Mapping[str, Any], known: Iterable[str], owner: str = '', reason: str = ''
) -> str:
    """`unknown parameter pd.omega=20.0 (did you mean pd.omega_c?): OWNER has no such
    parameter` (or `: REASON`); several names in one line."""
    known = list(known)
    parts = []
    for name in sorted(given):
        close = difflib.get_close_matches(name, known, n=1)
        hint = f' (did you mean {close[0]}?)' if close else ''
        parts.append(f'{name}={shown(given[name])}{hint}')
    s = 's' if len(parts) > 1 else ''
    reason = reason or f'{owner} has no such parameter{s}'
    return f'unknown parameter{s} {", ".join(parts)}: {reason}'


# Parameters rclpy declares on every node by itself; `qos_overrides.` parameters too, when a
# publisher or subscription is created with QoS overriding options.
ROS_PARAMETERS = frozenset({'use_sim_time', 'start_type_description_service'})
ROS_PARAMETER_PREFIXES = ('qos_overrides.',)


def is_ros_parameter(name: str) -> bool:
    return name in ROS_PARAMETERS or name.startswith(ROS_PARAMETER_PREFIXES)


def ros_parameter_problem(name: str, value: Any) -> str | None:
    """Why rclpy would refuse `value` for a parameter it declares itself (both of
    ROS_PARAMETERS are booleans), in one line; None if it would not (or it is not one)."""
    if name in ROS_PARAMETERS and not isinstance(value, bool):
        return f'invalid parameter {name}={shown(value)}: must be true or false'
    return None


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


class Finite(Constraint):
    text = 'a finite number'

    def __call__(self, value: Any) -> str | None:
        if not _is_number(value) or not math.isfinite(value):
            return 'must be a finite number'
        return None


number = Finite()


class Above(Constraint):
    """A finite number > lo (or also +inf)."""

    low_open = True

    def __init__(self, lo: float, or_inf: bool = False) -> None:
        self.lo = lo
        self.or_inf = or_inf
        self.bounds = (lo, math.inf)
        self.text = f'> {lo:g}' + (', or .inf (no limit)' if or_inf else '')

    def __call__(self, value: Any) -> str | None:
        if self.or_inf and _is_number(value) and value == math.inf:
            return None
        return number(value) or (None if value > self.lo else f'must be > {self.lo:g}')


class AtLeast(Constraint):
    """A finite number >= lo."""

    def __init__(self, lo: float) -> None:
        self.lo = lo
        self.bounds = (lo, math.inf)
        self.text = f'>= {lo:g}'

    def __call__(self, value: Any) -> str | None:
        return number(value) or (None if value >= self.lo else f'must be >= {self.lo:g}')


positive = Above(0)
non_negative = AtLeast(0)
positive_or_inf = Above(0, or_inf=True)


class Between(Constraint):
    """A finite number in [lo, hi]."""

    def __init__(self, lo: float, hi: float) -> None:
        self.lo, self.hi = lo, hi
        self.bounds = (lo, hi)
        self.text = f'in [{lo}, {hi}]'

    def __call__(self, value: Any) -> str | None:
        if number(value):
            return number(value)
        return None if self.lo <= value <= self.hi else f'must be in [{self.lo}, {self.hi}]'


def in_range(lo: float, hi: float) -> Between:
    return Between(lo, hi)


class WholeAtLeast(Constraint):
    """A whole number (not a bool) >= lo."""

    def __init__(self, lo: int) -> None:
        self.lo = lo
        self.bounds = (lo, math.inf)
        self.text = f'a whole number >= {lo}'

    def __call__(self, value: Any) -> str | None:
        if not isinstance(value, int) or isinstance(value, bool) or value < self.lo:
            return f'must be a whole number >= {self.lo}'
        return None


positive_int = WholeAtLeast(1)
non_negative_int = WholeAtLeast(0)


class WholeIn(Constraint):
    """A whole number (not a bool) in [lo, hi]: a count whose size drives memory or CPU time
    (substeps, taps, grid intervals, samples of delay) is bounded, so that no value can
    make a node run out of either."""

    def __init__(self, lo: int, hi: int) -> None:
        self.lo, self.hi = lo, hi
        self.bounds = (lo, hi)
        self.text = f'a whole number in [{lo}, {hi}]'

    def __call__(self, value: Any) -> str | None:
        if not isinstance(value, int) or isinstance(value, bool) or not self.lo <= value <= self.hi:
            return f'must be {self.text}'
        return None


def whole_in(lo: int, hi: int) -> WholeIn:
    return WholeIn(lo, hi)


class OneOf(Constraint):
    def __init__(self, choices: Sequence[str]) -> None:
        self.choices = tuple(choices)
        self.text = f'one of: {", ".join(self.choices)}'

    def __call__(self, value: Any) -> str | None:
        return None if value in self.choices else f'must be {self.text}'


def one_of(*choices: str) -> OneOf:
    return OneOf(choices)


class Boolean(Constraint):
    def __call__(self, value: Any) -> str | None:
        return None if isinstance(value, bool) else 'must be true or false'


class Text(Constraint):
    def __call__(self, value: Any) -> str | None:
        return None if isinstance(value, str) else 'must be a string'


boolean = Boolean()
text = Text()


class NumberList(Constraint):
    """A list of numbers, optionally of a fixed length, each passing `each`."""

    value_type = 'double_array'

    def __init__(self, length: int | None = None, each: Check = number) -> None:
        self.length = length
        self.each = each
        count = f'{length} numbers' if length is not None else 'numbers'
        each_text = getattr(each, 'text', '')
        show = each_text and each is not number
        self.text = f'a list of {count}' + (f', each {each_text}' if show else '')

    def __call__(self, value: Any) -> str | None:
        if not isinstance(value, list | tuple):
            return 'must be a list of numbers'
        if self.length is not None and len(value) != self.length:
            return f'must have {self.length} entries, got {len(value)}'
        for i, item in enumerate(value):
            reason = self.each(item)
            if reason:
                return f'entry {i} {reason}'
        return None


def number_list(length: int | None = None, each: Check = number) -> NumberList:
    return NumberList(length, each)


class StringList(Constraint):
    """A list of strings."""

    value_type = 'string_array'

    def __init__(self, what: str = 'strings') -> None:
        self.what = what
        self.text = f'a list of {what}'

    def __call__(self, value: Any) -> str | None:
        if isinstance(value, list | tuple) and all(isinstance(v, str) for v in value):
            return None
        return f'must be a list of {self.what}'


# -- value types ---------------------------------------------------------------------------------
# The ROS parameter types a spec can have, with how an error message says them.
VALUE_TYPES = {
    'bool': 'true or false',
    'integer': 'a whole number',
    'double': 'a floating-point number',
    'string': 'a string',
    'bool_array': 'a list of true/false',
    'integer_array': 'a list of whole numbers',
    'double_array': 'a list of numbers',
    'string_array': 'a list of strings',
}


def type_of(value: Any) -> str:
    """The parameter type of a value (`double` for 1.5, `string_array` for ['a']); for
    anything a parameter cannot hold, a plain word (`null`, `mapping`, `mixed list`)."""
    if isinstance(value, bool):
        return 'bool'
    if isinstance(value, int):
        return 'integer'
    if isinstance(value, float):
        return 'double'
    if isinstance(value, str):
        return 'string'
    if isinstance(value, list | tuple):
        kinds = {type_of(v) for v in value}
        if len(kinds) == 1 and (kind := kinds.pop()) in ('bool', 'integer', 'double', 'string'):
            return kind + '_array'
        return 'empty list' if not value else 'mixed list'
    if value is None:
        return 'null'
    return 'mapping' if isinstance(value, dict) else type(value).__name__


def value_type(spec: ParamSpec) -> str:
    """The type of a spec's parameter: that of its default, or what its check names for a
    list whose default is empty."""
    kind = type_of(spec.default)
    if kind in VALUE_TYPES:
        return kind
    named = getattr(spec.check, 'value_type', None)
    if named in VALUE_TYPES:
        return named
    raise ValueError(f'parameter {spec.name}: cannot tell its type from default {spec.default!r}')


def type_mismatch(spec: ParamSpec, value: Any) -> str | None:
    """None if `value` (coerced) has the spec's type, else the reason in words."""
    expected = value_type(spec)
    got = type_of(value)
    if got == expected or (got == 'empty list' and expected.endswith('_array')):
        return None
    return f'must be of type {expected} ({VALUE_TYPES[expected]}), got {got}'


def coerce(spec: ParamSpec, value: Any) -> Any:
    """Accept an integer where a float is expected (YAML writes 12 for 12.0)."""
    if isinstance(spec.default, float) and _is_number(value):
        return float(value)
    is_float_list = isinstance(spec.default, list | tuple) and bool(spec.default)
    if is_float_list and isinstance(spec.default[0], float) and isinstance(value, list | tuple):
        return [float(v) if _is_number(v) else v for v in value]
    return value


def validate(spec: ParamSpec, value: Any, full_name: str | None = None) -> Any:
    """Return the coerced value, or raise ParameterError with the reason.

    A value of the wrong type is refused naming the expected type; for a list parameter
    its own check speaks first, as it names the entry that is wrong (`entry 1 must be > 0`).
    """
    value = coerce(spec, value)
    if value_type(spec).endswith('_array'):
        reason = spec.check(value) or type_mismatch(spec, value)
    else:
        reason = type_mismatch(spec, value) or spec.check(value)
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


def check_gain_and_period(input_gain: float, sample_period: float) -> tuple[float, float]:
    """(b, T) as floats, or ParameterError naming the bad one."""
    b = float(input_gain)
    if not math.isfinite(b) or b == 0.0:
        raise ParameterError('input_gain', input_gain, 'must be finite and non-zero')
    reason = positive(sample_period)
    if reason:
        raise ParameterError('sample_period', sample_period, reason)
    return b, float(sample_period)


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
