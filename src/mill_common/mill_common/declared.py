"""Parameters declared once, typed: the fields of a frozen dataclass. ROS-free.

A core's parameters are one `ParamSet` subclass; each field is made by `param()` with its
default, description, unit, check, `read_only` (keyword-only) and, where 0 means "the
tuning rule's value", the rule's quantity it stands for. From that one declaration come:

- the `ParamSpec` of each parameter (`specs()`): ROS descriptors, `--help`, docs tables;
- validation: making a ParamSet checks every field, so an instance is always valid
  (a wrong value raises ParameterError naming `PREFIX.name`);
- `from_values()`: the set from a node's or a file's mapping, unknown names refused;
- `tuned()`: the set with the tuning rule's values put where the declaration asks for them.

The model is ros2_controllers' generate_parameter_library YAML (type, default,
description, read_only and validation, by name), written as a Python dataclass.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar, TypeVar

from mill_common.parameters import (
    Check,
    ParamSpec,
    UnknownParameterError,
    no_check,
    validate,
)

S = TypeVar('S', bound='ParamSet')
_KEY = 'mill.param'


@dataclass(frozen=True)
class Declaration:
    """What a field declares beside its default (kept in the field's metadata)."""

    description: str
    check: Check
    unit: str
    read_only: bool
    rule: str  # the tuning rule's quantity a value of 0 stands for ('' none)


def param(
    default: Any,
    description: str,
    check: Check = no_check,
    *,
    unit: str = '',
    read_only: bool = False,
    rule: str = '',
) -> Any:
    """A parameter field: default, description, check, unit and flags, declared once.

    unit is shown after the description (`[rad/s]`); rule names the quantity of the tuning
    rule (mill_models.loop_tuning) that the value 0 stands for: the description says so.
    """
    if rule:
        description += f"; 0 = the tuning rule's {rule} for the sample period and delay"
    meta = {_KEY: Declaration(description, check, unit, read_only, rule)}
    if isinstance(default, list):
        items = list(default)
        return field(default_factory=lambda: list(items), metadata=meta)
    return field(default=default, metadata=meta)


@dataclass(frozen=True)
class ParamSet:
    """Base of a core's parameters; subclasses are frozen dataclasses of `param()` fields.

    PREFIX is the namespace of the parameters' full names (`pd` → `pd.omega_c`); '' for a
    node's own parameters.
    """

    PREFIX: ClassVar[str] = ''

    def __post_init__(self) -> None:
        for spec in type(self).specs():
            value = validate(spec, getattr(self, spec.name), type(self).full_name(spec.name))
            object.__setattr__(self, spec.name, value)

    @classmethod
    def full_name(cls, name: str) -> str:
        return f'{cls.PREFIX}.{name}' if cls.PREFIX else name

    @classmethod
    def specs(cls) -> tuple[ParamSpec, ...]:
        """The ParamSpec of every field, in declaration order (names without PREFIX)."""
        return _specs(cls)

    @classmethod
    def named_specs(cls, read_only: bool = False) -> list[tuple[str, ParamSpec]]:
        """(full name, spec) of every field; read_only: all of them read-only."""
        return [
            (cls.full_name(s.name), dataclasses.replace(s, read_only=True) if read_only else s)
            for s in cls.specs()
        ]

    @classmethod
    def from_values(cls: type[S], values: Mapping[str, Any], owner: str = '') -> S:
        """The set from a mapping keyed by names without PREFIX; missing names take their
        defaults, a name the set does not declare is refused (UnknownParameterError)."""
        names = {s.name for s in cls.specs()}
        unknown = {n: v for n, v in values.items() if n not in names}
        if unknown:
            raise UnknownParameterError(unknown, names, owner or cls.__name__)
        return cls(**dict(values))

    @classmethod
    def from_node_values(cls: type[S], values: Mapping[str, Any]) -> S:
        """The set out of a node's values, keyed by full names (other names are ignored)."""
        return cls(
            **{
                s.name: values[cls.full_name(s.name)]
                for s in cls.specs()
                if cls.full_name(s.name) in values
            }
        )

    def values(self) -> dict[str, Any]:
        """name (without PREFIX) → value."""
        return {s.name: getattr(self, s.name) for s in self.specs()}

    def replace(self: S, **changes: Any) -> S:
        """A copy with `changes`, validated as any new set is."""
        return dataclasses.replace(self, **changes)

    def tuned(self: S, rule: Mapping[str, float]) -> S:
        """The set with each field whose declaration names a rule quantity and whose value
        is 0 given that quantity's value (rule: quantity name → value)."""
        changes = {}
        for f in dataclasses.fields(self):
            declared = f.metadata.get(_KEY)
            if declared and declared.rule and getattr(self, f.name) == 0:
                changes[f.name] = float(rule[declared.rule])
        return self.replace(**changes) if changes else self

    @classmethod
    def rule_fields(cls) -> dict[str, str]:
        """name → the rule quantity its 0 stands for, for the fields that declare one."""
        return {
            f.name: f.metadata[_KEY].rule
            for f in dataclasses.fields(cls)
            if _KEY in f.metadata and f.metadata[_KEY].rule
        }


_SPECS: dict[type[ParamSet], tuple[ParamSpec, ...]] = {}


def _specs(cls: type[ParamSet]) -> tuple[ParamSpec, ...]:
    if cls in _SPECS:
        return _SPECS[cls]
    out = []
    for f in dataclasses.fields(cls):
        base = _declaring_base(cls, f)
        if base is not None:  # a field of a base set: the base's spec itself, shared
            out.append(next(s for s in _specs(base) if s.name == f.name))
            continue
        declared: Declaration | None = f.metadata.get(_KEY)
        if declared is None:
            raise TypeError(f'{cls.__name__}.{f.name} is not declared with param()')
        if f.default is not dataclasses.MISSING:
            default = f.default
        elif f.default_factory is not dataclasses.MISSING:
            default = f.default_factory()
        else:
            raise TypeError(f'{cls.__name__}.{f.name} has no default')
        unit = f' [{declared.unit}]' if declared.unit else ''
        out.append(
            ParamSpec(
                f.name,
                default,
                declared.description + unit,
                declared.check,
                read_only=declared.read_only,
                unit=declared.unit,
            )
        )
    _SPECS[cls] = tuple(out)
    return _SPECS[cls]


def _declaring_base(cls: type[ParamSet], f: dataclasses.Field[Any]) -> type[ParamSet] | None:
    """The base set (a ParamSet subclass) whose field f is, if cls inherits it."""
    for base in cls.__mro__[1:]:
        inherits = issubclass(base, ParamSet) and base is not ParamSet
        if inherits and getattr(base, '__dataclass_fields__', {}).get(f.name) is f:
            return base
    return None


class Configured:
    """A core whose parameters are one ParamSet (PARAMS): its PREFIX and PARAMETERS, which
    registries and nodes read, are derived from it, never written a second time."""

    PARAMS: ClassVar[type[ParamSet]] = ParamSet
    PREFIX: ClassVar[str] = ''
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]] = ()

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if 'PARAMS' in vars(cls):
            cls.PREFIX = cls.PARAMS.PREFIX
            cls.PARAMETERS = cls.PARAMS.specs()
