"""Name → class registries, the one way every plugin is chosen by a parameter. ROS-free.

A registry maps the values of one selecting parameter (`controller`, `observer`,
`cutting_model`, ...) to classes. Each registered class names its parameter namespace
(PREFIX) and lists its parameters (PARAMETERS); the registry hands out the class for a
name, refuses an unknown name with a ParameterError naming the choices, and collects the
parameters of all its classes under their prefixes, so that a node declares them all.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping
from dataclasses import replace
from typing import Generic, TypeVar

from mill_common.parameters import (
    Check,
    ParameterError,
    ParamSpec,
    Plugin,
    algorithm_specs,
    one_of,
)

T = TypeVar('T', bound=Plugin)  # the role's base class (AxisController, Observer, ...)


class Registry(Generic[T]):
    """The classes one parameter chooses among, in a fixed order (the order of `entries`)."""

    def __init__(self, parameter: str, entries: Mapping[str, type[T]]) -> None:
        for name, cls in entries.items():
            if not cls.PREFIX:
                raise TypeError(f'{parameter} {name!r}: {cls.__name__} has no PREFIX')
        self.parameter = parameter
        self._entries: dict[str, type[T]] = dict(entries)

    def get(self, name: object) -> type[T]:
        """The class registered as `name`; ParameterError(parameter, name, choices) if none."""
        if isinstance(name, str) and name in self._entries:
            return self._entries[name]
        raise ParameterError(self.parameter, name, f'must be one of: {", ".join(self._entries)}')

    def names(self) -> tuple[str, ...]:
        """The registered names, in registration order."""
        return tuple(self._entries)

    def name_of(self, cls: type) -> str | None:
        """The first name `cls` is registered under (what to call a running instance of it);
        None if it is not registered."""
        return next((name for name, c in self._entries.items() if c is cls), None)

    def classes(self) -> tuple[type[T], ...]:
        """The registered classes, in registration order (a class registered twice once)."""
        return tuple(dict.fromkeys(self._entries.values()))

    def items(self) -> Iterable[tuple[str, type[T]]]:
        return self._entries.items()

    def check(self) -> Check:
        """The check of the selecting parameter: one of the registered names."""
        return one_of(*self._entries)

    def parameter_specs(
        self, read_only: bool = False, exclude: Iterable[str] = ()
    ) -> list[tuple[str, ParamSpec]]:
        """(PREFIX.name, spec) of every registered class, each full name once.

        read_only: every spec becomes read-only (parameters of cores built once per run).
        exclude: names whose classes' parameters are declared elsewhere.
        """
        skip = {self._entries[n] for n in exclude}
        specs = algorithm_specs(cls for cls in self.classes() if cls not in skip)
        return [(n, replace(s, read_only=True) if read_only else s) for n, s in specs]

    def __getitem__(self, name: object) -> type[T]:
        """registry[name] is registry.get(name): ParameterError for an unknown name."""
        return self.get(name)

    def __contains__(self, name: object) -> bool:
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)
