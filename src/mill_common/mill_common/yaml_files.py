"""YAML read from users' files, safely: one loader for every file the suite reads. ROS-free.

Parameter files (`--params-file` of a node or of run_scenario, a launch file's params_file),
scenario files, machine models, predictions and bag metadata are read by `read_yaml` (a
path) or `parse_yaml` (a text). Beside PyYAML's safe loader (no Python objects), they refuse
in one line (`YamlRefused`, a yaml.YAMLError):

- a file or text of more than MAX_YAML_BYTES (1 MiB): read no further;
- anchors and aliases (`&a`, `*a`): rcl refuses them in parameter files, the suite writes
  none, and nested aliases expand exponentially (a 478-byte "billion laughs" file became a
  140 MB error line and 632 MB of memory);
- nesting deeper than MAX_YAML_DEPTH levels (PyYAML composes recursively: a file of a few
  thousand `[` would end in a RecursionError).

`ros_floats=True` reads `1.37e9` as a float, as rcl does (PyYAML's YAML 1.1 wants a dot).
`yaml_problem(exc)` is the one line a caller prints for any of these or for invalid YAML.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import yaml
from yaml.events import AliasEvent, CollectionStartEvent, ScalarEvent
from yaml.nodes import Node

MAX_YAML_BYTES = 1 << 20  # 1 MiB: the largest parameter file of the suite is ~10 kB
MAX_YAML_DEPTH = 64  # nesting levels; a parameter file has 4 (node, ros__parameters, ...)


class YamlRefused(yaml.YAMLError):
    """A YAML file or text refused before or while it is read; str() is one line."""


class _Composer(yaml.SafeLoader):
    """The safe loader with anchors, aliases and deep nesting refused while composing."""

    _depth = 0

    def compose_node(self, parent: Node | None, index: Any) -> Node | None:
        event = self.peek_event()
        mark = event.start_mark
        where = f' at line {mark.line + 1}, column {mark.column + 1}' if mark else ''
        if isinstance(event, AliasEvent):
            raise YamlRefused(f'an alias (*{event.anchor}){where}: aliases are refused')
        if isinstance(event, ScalarEvent | CollectionStartEvent) and event.anchor is not None:
            raise YamlRefused(f'an anchor (&{event.anchor}){where}: anchors are refused')
        self._depth += 1
        try:
            if self._depth > MAX_YAML_DEPTH:
                raise YamlRefused(f'nested more than {MAX_YAML_DEPTH} levels deep{where}')
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


class _RosComposer(_Composer):
    """As rcl reads YAML: `1.37e9` is a float."""


_RosComposer.add_implicit_resolver(
    'tag:yaml.org,2002:float',
    re.compile(r'^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$'),
    list('-+0123456789'),
)


def _too_large() -> YamlRefused:
    return YamlRefused(f'larger than {MAX_YAML_BYTES} bytes (1 MiB), the most a YAML file may be')


def parse_yaml(text: str, ros_floats: bool = False) -> Any:
    """The document of `text` (YamlRefused, yaml.YAMLError)."""
    if len(text) > MAX_YAML_BYTES or len(text.encode('utf-8', 'surrogatepass')) > MAX_YAML_BYTES:
        raise _too_large()
    loader = (_RosComposer if ros_floats else _Composer)(text)
    try:
        return loader.get_single_data()
    finally:
        loader.dispose()


def read_yaml(path: str | Path, ros_floats: bool = False) -> Any:
    """The document of the file at `path`, read no further than the size limit.

    OSError, UnicodeDecodeError as reading raises them; YamlRefused, yaml.YAMLError.
    """
    with open(path, 'rb') as f:
        data = f.read(MAX_YAML_BYTES + 1)
    if len(data) > MAX_YAML_BYTES:
        raise _too_large()
    return parse_yaml(data.decode('utf-8'), ros_floats)


def yaml_problem(exc: yaml.YAMLError) -> str:
    """What is wrong with a YAML text, in one line: a refusal's own words, or `not valid
    YAML (PROBLEM at line L, column C)`."""
    if isinstance(exc, YamlRefused):
        return str(exc)
    mark = getattr(exc, 'problem_mark', None)
    problem = getattr(exc, 'problem', None) or type(exc).__name__
    where = f' at line {mark.line + 1}, column {mark.column + 1}' if mark else ''
    return ' '.join(f'not valid YAML ({problem}{where})'.split())
