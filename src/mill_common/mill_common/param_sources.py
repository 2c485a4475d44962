"""Where a node's parameter values come from: `-p` arguments and parameter files. ROS-free.

rcl merges every source into one set of overrides per node and does not say where a value
came from. A node needs that to tell a typo from a value meant for other nodes:

- direct: `-p NAME:=VALUE` (or `-p NODE:NAME:=VALUE` for this node) and the entries of a
  parameter file under this node's own name (`x_controller:` or `/x_controller:`, or its
  fully qualified name). A name given directly that the node does not declare is an error.
- shared: the entries of a parameter file under a key with a wildcard (`/**:`, `/**/name:`,
  `/*:` ...), which one file gives to every node it starts. A node takes the ones it
  declares and ignores the rest; whether every shared name is declared by some node is a
  question about the whole graph, which `run_scenario` answers for a scenario file.

Only the `--ros-args` part of the command line is read (up to `--`), as rcl does.

A parameter file that sets nothing (empty, or no `ros__parameters` values), or nothing for
the nodes of the process it is given to, is refused: a node would otherwise start on its
defaults without a word (a following-error limit of 5 mm instead of the scenario's 1 mm).
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from mill_common.yaml_files import read_yaml, yaml_problem

PARAMETER_FLAGS = ('-p', '--param')
PARAMS_FILE_FLAG = '--params-file'
ROS_PARAMETERS_KEY = 'ros__parameters'


@dataclass
class ParameterSources:
    """Names given to one node, by where they came from."""

    direct: set[str] = field(default_factory=set)
    shared: set[str] = field(default_factory=set)
    files: list[str] = field(default_factory=list)


def ros_arguments(argv: Sequence[str]) -> list[str]:
    """The tokens of every `--ros-args ... [--]` section of a command line."""
    out: list[str] = []
    inside = False
    for token in argv:
        if token == '--ros-args':
            inside = True
        elif token == '--' and inside:
            inside = False
        elif inside:
            out.append(token)
    return out


def _flag_values(args: Sequence[str], flags: Sequence[str]) -> list[str]:
    return [args[i + 1] for i, token in enumerate(args[:-1]) if token in flags]


def params_files(argv: Sequence[str]) -> list[str]:
    return _flag_values(ros_arguments(argv), (PARAMS_FILE_FLAG,))


def flatten(params: Mapping[str, Any], prefix: str = '') -> dict[str, Any]:
    """Nested parameter mappings as rcl reads them: {'pd': {'omega_c': 12}} -> pd.omega_c."""
    out: dict[str, Any] = {}
    for key, value in params.items():
        name = f'{prefix}{key}'
        if isinstance(value, Mapping):
            out.update(flatten(value, name + '.'))
        else:
            out[name] = value
    return out


def node_entries(document: Any) -> Iterator[tuple[str, dict[str, Any]]]:
    """(node key, flattened parameters) of every `ros__parameters` block of a parameter file.

    Nested namespace keys are joined as rcl joins them (`/ns: node:` -> `/ns/node`).
    """

    def walk(node: Any, path: list[str]) -> Iterator[tuple[str, dict[str, Any]]]:
        if not isinstance(node, Mapping):
            return
        for key, value in node.items():
            if key == ROS_PARAMETERS_KEY:
                key_path = '/' + '/'.join(str(p).strip('/') for p in path)
                yield key_path, flatten(value) if isinstance(value, Mapping) else {}
            else:
                yield from walk(value, [*path, str(key)])

    yield from walk(document, [])


def _for_node(key: str, node_name: str, fqn: str) -> bool:
    """Whether the node part of a `-p NODE:NAME:=VALUE` rule names this node."""
    stripped = key.strip('/')
    return stripped in (node_name, fqn.strip('/'))


_KEY_TOKENS = {'**': '(?:/[^/]+)*', '*': '/[^/]+'}


def key_matches(key: str, fqn: str) -> bool:
    """Whether the entry `key` of a parameter file applies to the node named `fqn`, as rcl
    (Jazzy) matches it: `*` is one name token, `**` any number of them (none too), a key
    without a leading slash is from the root (`x_controller` is /x_controller only)."""
    pattern = ''.join(_KEY_TOKENS.get(t, '/' + re.escape(t)) for t in key.split('/') if t)
    return re.fullmatch(pattern, fqn) is not None


def parameter_sources(argv: Sequence[str], node_name: str, fqn: str) -> ParameterSources:
    """The names given to node `node_name` (fully qualified `fqn`), direct or shared.

    Parameter files are assumed readable (rcl has read them by the time a node exists).
    """
    args = ros_arguments(argv)
    sources = ParameterSources()
    for rule in _flag_values(args, PARAMETER_FLAGS):
        target, sep, _value = rule.partition(':=')
        if not sep:
            continue
        node, colon, name = target.rpartition(':')
        if not colon or '*' in node or _for_node(node, node_name, fqn):
            sources.direct.add(name)
    for path in _flag_values(args, (PARAMS_FILE_FLAG,)):
        sources.files.append(path)
        try:
            document = read_yaml(path)
        except (OSError, UnicodeDecodeError, yaml.YAMLError):
            continue
        for key, params in node_entries(document):
            if not key_matches(key, fqn):
                continue
            if '*' in key:
                sources.shared.update(params)
            else:
                sources.direct.update(params)
    return sources


def parameter_rules(argv: Sequence[str]) -> list[str]:
    """The `-p` / `--param` arguments of a command line."""
    return _flag_values(ros_arguments(argv), PARAMETER_FLAGS)


def parameter_rule_problem(rule: str) -> str | None:
    """Why a `-p` argument is not `NAME:=VALUE` (or `NODE:NAME:=VALUE`); None if it is."""
    target, sep, _value = rule.partition(':=')
    name = target.rpartition(':')[2]
    if not sep or not name:
        return 'not NAME:=VALUE'
    return None


def params_file_problem(path: str) -> str | None:
    """Why a --params-file cannot be read or sets nothing, in words; None if it reads as
    YAML and sets at least one parameter.

    What rcl refuses in a well-formed YAML file (a value before `ros__parameters`, a list
    of mixed types) rcl reports itself; see `rcl_error_message`.
    """
    p = Path(path)
    if not p.exists():
        return 'no such file'
    if p.is_dir():
        return 'is a directory, not a parameter file'
    try:
        document = read_yaml(p)
    except OSError as exc:
        return exc.strerror or str(exc)
    except UnicodeDecodeError:
        return 'not a text file'
    except yaml.YAMLError as exc:
        return yaml_problem(exc)
    if any(values for _key, values in node_entries(document)):
        return None
    if document is None:
        return 'empty: it sets no parameter'
    return f'no {ROS_PARAMETERS_KEY} values: it sets no parameter'


def params_file_miss(path: str, fqns: Sequence[str]) -> str | None:
    """Why a parameter file gives the nodes `fqns` (those of one process) nothing, in words;
    None if one of its entries with values applies to one of them, or if it cannot be read
    (params_file_problem and rcl say why)."""
    try:
        document = read_yaml(path)
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return None
    keys = list(dict.fromkeys(key for key, values in node_entries(document) if values))
    if any(key_matches(key, fqn) for key in keys for fqn in fqns):
        return None
    shown = ', '.join(keys[:MAX_KEYS_SHOWN]) + (', ...' if len(keys) > MAX_KEYS_SHOWN else '')
    return f'nothing in it is for {" or ".join(fqns)} (its entries: {shown or "none"})'


MAX_KEYS_SHOWN = 6  # of a file refused by params_file_miss, in its one line


def rcl_error_message(message: str) -> str:
    """rcl's error text in one line without its C source locations.

    "failed to initialize rcl: Couldn't parse params file: '--params-file F'. Error: Cannot
    have a value before ros__parameters at line 1, at /src/parse.c:806, at ..." ->
    "--params-file F: cannot have a value before ros__parameters at line 1".
    """
    text = ' '.join(message.split())
    parts = [p.strip() for p in text.split(', at ') if not _is_source_location(p)]
    text = ', at '.join(parts)
    text = text.removeprefix('failed to initialize rcl: ')
    for lead in ("Couldn't parse params file: ", "Couldn't parse parameter override rule: "):
        if text.startswith(lead):
            rest = text[len(lead) :]
            what, _sep, error = rest.partition('. Error: ')
            what = what.strip("'")
            error = error[:1].lower() + error[1:]
            return f'{what}: {error}' if error else what
    return text


def _is_source_location(part: str) -> bool:
    head, colon, line = part.rpartition(':')
    return bool(colon) and line.isdigit() and head.endswith(('.c', '.cpp', '.h', '.hpp'))
