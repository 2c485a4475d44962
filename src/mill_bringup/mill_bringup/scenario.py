"""Scenario files: ROS 2 parameter files with a `mill_scenario` entry listing the nodes. ROS-free.

The same file feeds `ros2 run ... --params-file`, the runner and the offline
simulator, so a scenario is defined once.

A node's entry may be keyed `/**/NAME` (applies in any namespace, as the files in config/
are), `NAME` or `/NAME` (only in the root namespace, as rcl reads parameter files).
`mill_scenario` may name a `namespace` for the whole graph and ask for a `private_clock`
(the simulation's /clock remapped into that namespace, so that two simulated machines can
share a domain). `node_parameters` gives every node its merged values keyed `/**/NAME`, so
the runner and the launch file apply them in any namespace.
"""

from __future__ import annotations

import fnmatch
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml
from mill_common.param_sources import flatten
from mill_common.parameters import (
    ParameterError,
    ParamSpec,
    is_ros_parameter,
    ros_parameter_problem,
    unknown_parameters_message,
    validate,
)

from mill_bringup.catalogue import NodeKind, UnknownNodeKind, kind_of
from mill_common import topics, yaml_files

SCENARIO_KEY = 'mill_scenario'
SHARED_KEY = '/**'  # what a parameter file gives every node
# Which nodes share a process (mill_bringup.layout); `layout:` in mill_scenario, --layout.
LAYOUTS = ('processes', 'per_axis', 'single')


def check_layout(value: object) -> str:
    """The layout named by value; ScenarioError (one line) if it names none."""
    if value not in LAYOUTS:
        raise ScenarioError(f'layout must be one of {", ".join(LAYOUTS)}, got {value!r}')
    return str(value)


def parse_yaml(text: str) -> Any:
    """YAML as ROS reads parameter files (`1.37e9` is a float), read safely
    (mill_common.yaml_files: no aliases, at most 1 MiB)."""
    return yaml_files.parse_yaml(text, ros_floats=True)


class _Dumper(yaml.SafeDumper):
    """Parameter files for rcl: every string quoted (rcl reads a bare `y` or `no` as bool),
    no anchors and aliases (rcl refuses them)."""

    def ignore_aliases(self, data: Any) -> bool:
        return True


_Dumper.add_representer(
    str, lambda dumper, value: dumper.represent_scalar('tag:yaml.org,2002:str', value, style='"')
)


def dump_parameters(data: dict[str, Any]) -> str:
    """YAML text of a parameter file that rcl reads as parse_yaml does."""
    return yaml.dump(data, Dumper=_Dumper, sort_keys=False, allow_unicode=True)


def parameter_specs_of(launch: NodeLaunch) -> list[tuple[str, ParamSpec]]:
    """The parameter specs of the node this launch entry starts."""
    return launch.kind.parameter_specs()


class ScenarioError(ValueError):
    """A scenario file or override that cannot be used; str() says why in one line."""


@dataclass(frozen=True)
class NodeLaunch:
    name: str
    package: str
    executable: str

    @property
    def kind(self) -> NodeKind:
        """What this node is (mill_bringup.catalogue); checked when the scenario loads."""
        return kind_of(self.package, self.executable)


@dataclass
class Scenario:
    path: Path
    description: str
    nodes: list[NodeLaunch]
    raw: dict[str, Any]
    overrides: dict[str, dict[str, Any]] = field(default_factory=dict)
    # Configurations compared by one run: name -> overrides (`variants:` in the file).
    variants: dict[str, list[str]] = field(default_factory=dict)
    paper: str = ''  # which paper's metrics the run prints (mill_analysis.papers)
    namespace: str = topics.ROOT  # the machine namespace every node of the graph runs in
    private_clock: bool = False  # remap the simulation's /clock to NAMESPACE/clock
    layout: str = LAYOUTS[0]  # which nodes share a process (mill_bringup.layout)
    params_files: list[str] = field(default_factory=list)  # applied with apply_params_file

    @property
    def name(self) -> str:
        return self.path.stem

    def node(self, name: str) -> NodeLaunch:
        for n in self.nodes:
            if n.name == name:
                return n
        raise ScenarioError(f'scenario {self.name} has no node {name!r}')

    def nodes_of(self, role: str) -> list[NodeLaunch]:
        """The nodes of one role (mill_bringup.catalogue: PLANT, CONTROLLER, ...)."""
        return [n for n in self.nodes if n.kind.role == role]

    def _entry(self, key: str) -> dict[str, Any]:
        entry = self.raw.get(key)
        params = entry.get('ros__parameters') if isinstance(entry, dict) else None
        return flatten(params) if isinstance(params, dict) else {}

    def given_parameters(self, name: str) -> dict[str, Any]:
        """What is given to this node alone: its own entry, then the overrides."""
        merged: dict[str, Any] = {}
        for key in (name, '/' + name, '/**/' + name):
            merged.update(self._entry(key))
        merged.update(self.overrides.get(name, {}))
        return merged

    def raw_parameters(self, name: str) -> dict[str, Any]:
        """Parameters a node of this name gets: /** entries, then its own, then overrides."""
        return {**self._entry(SHARED_KEY), **self.given_parameters(name)}

    def node_parameters(self) -> dict[str, Any]:
        """A parameter file's content: every node's merged values, keyed to apply anywhere."""
        return {
            f'/**/{n.name}': {'ros__parameters': self.raw_parameters(n.name)} for n in self.nodes
        }

    def set_namespace(self, text: str) -> None:
        """The machine namespace of the graph ('' or '/' is the root)."""
        try:
            self.namespace = topics.namespace(text)
        except ValueError as exc:
            raise ScenarioError(str(exc)) from None

    def remappings(self) -> list[str]:
        """ROS remapping rules every node of the graph gets (`-r RULE`)."""
        rules = []
        if self.namespace != topics.ROOT:
            rules.append(f'__ns:={self.namespace}')
            if self.private_clock:
                rules.append(f'{topics.CLOCK}:={topics.clock(self.namespace, private=True)}')
        return rules

    def parameters(self, name: str) -> dict[str, Any]:
        """Validated parameter values of one node, as its node would hold them.

        A name given to this node alone (its own entry, an override) that it does not
        declare is refused, as the node itself would refuse it; `/**` names are checked
        against every node at load time.
        """
        launch = self.node(name)
        specs = parameter_specs_of(launch)
        known = {full for full, _spec in specs}
        unknown = {
            n: v
            for n, v in self.given_parameters(name).items()
            if n not in known and not is_ros_parameter(n)
        }
        if unknown:
            message = unknown_parameters_message(unknown, known, name)
            raise ScenarioError(f'{self.path}: entry {name}: {message}')
        raw = self.raw_parameters(name)
        for n, v in raw.items():  # rclpy's own (use_sim_time): the node would end on them
            problem = ros_parameter_problem(n, v)
            if problem:
                raise ScenarioError(f'{name}: {problem}')
        values = {}
        for full, spec in specs:
            try:
                values[full] = validate(spec, raw.get(full, spec.default), full)
            except ParameterError as exc:
                raise ScenarioError(f'{name}: {exc}') from None
        return values

    def variant(self, name: str) -> Scenario:
        """A copy of this scenario with the overrides of variant `name` applied."""
        if name not in self.variants:
            known = ', '.join(self.variants) or 'none'
            raise ScenarioError(f'scenario {self.name} has no variant {name!r} (has: {known})')
        copy = Scenario(
            self.path,
            self.description,
            self.nodes,
            self.raw,
            paper=self.paper,
            namespace=self.namespace,
            private_clock=self.private_clock,
            layout=self.layout,
            params_files=list(self.params_files),
        )
        copy.overrides = {node: dict(values) for node, values in self.overrides.items()}
        for text in self.variants[name]:
            copy.add_override(text)
        return copy

    def declares(self, node: str, param: str) -> bool:
        """Whether node `node` of the scenario declares parameter `param` (or ROS does)."""
        specs = parameter_specs_of(self.node(node))
        return is_ros_parameter(param) or any(full == param for full, _spec in specs)

    def check_shared(self) -> None:
        """Every top-level entry is for a node of the scenario, /** or mill_scenario, and
        every /** name is declared by some node of the scenario (or by ROS)."""
        names = {n.name for n in self.nodes}
        for key in self.raw or {}:
            node = str(key).removeprefix('/**/').strip('/')
            if key not in (SHARED_KEY, SCENARIO_KEY) and node not in names:
                raise ScenarioError(
                    f'{self.path}: entry {key!r} is for no node of the scenario '
                    f'(nodes: {", ".join(sorted(names))}; {SHARED_KEY} is for all of them)'
                )
        known = {full for n in self.nodes for full, _spec in parameter_specs_of(n)}
        unknown = {
            n: v
            for n, v in self._entry(SHARED_KEY).items()
            if n not in known and not is_ros_parameter(n)
        }
        if unknown:
            them = 'them' if len(unknown) > 1 else 'it'
            reason = f'no node of scenario {self.name} declares {them}'
            message = unknown_parameters_message(unknown, known, reason=reason)
            raise ScenarioError(f'{self.path}: {SHARED_KEY}: {message}')

    def add_override(self, text: str) -> None:
        """NODE.NAME=VALUE, NODE may be a glob (`*_controller.controller=pd`)."""
        target, sep, value_text = text.partition('=')
        node_glob, dot, param = target.partition('.')
        if not sep or not dot or not param:
            raise ScenarioError(f'override {text!r} is not NODE.NAME=VALUE')
        try:
            value = parse_yaml(value_text)
        except yaml_files.YamlRefused as exc:
            raise ScenarioError(f'override {text!r}: {exc}') from None
        except yaml.YAMLError:
            raise ScenarioError(f'override {text!r}: value is not valid YAML') from None
        matched = [n.name for n in self.nodes if fnmatch.fnmatchcase(n.name, node_glob)]
        if not matched:
            raise ScenarioError(f'override {text!r} matches no node of scenario {self.name}')
        # A glob gives the value to the matched nodes that declare the name; a node named
        # exactly must declare it. A name that no matched node declares is refused.
        declaring = [n for n in matched if self.declares(n, param)]
        if not declaring:
            known = {full for n in matched for full, _s in parameter_specs_of(self.node(n))}
            reason = f'{matched[0]} has no such parameter'
            if len(matched) > 1:
                reason = f'none of {", ".join(matched)} declares it'
            message = unknown_parameters_message({param: value}, known, reason=reason)
            raise ScenarioError(f'override {text!r}: {message}')
        for name in declaring:
            self.overrides.setdefault(name, {})[param] = value


def config_dirs() -> list[Path]:
    """Where scenario names are looked up: the source tree, then an installed share dir."""
    dirs = [Path(__file__).resolve().parents[3] / 'config']
    try:
        from ament_index_python.packages import get_package_share_directory

        dirs.append(Path(get_package_share_directory('mill_bringup')) / 'config')
    except Exception:
        pass
    return dirs


def resolve(name_or_path: str) -> Path:
    path = Path(name_or_path)
    if path.is_file():
        return path
    for d in config_dirs():
        candidate = d / f'{name_or_path}.yaml'
        if candidate.is_file():
            return candidate
    known = sorted({p.stem for d in config_dirs() if d.is_dir() for p in d.glob('*.yaml')})
    raise ScenarioError(
        f'no scenario {name_or_path!r} (a file, or one of: {", ".join(known) or "none"})'
    )


def load(name_or_path: str) -> Scenario:
    path = resolve(name_or_path)
    try:
        raw = yaml_files.read_yaml(path, ros_floats=True)
    except yaml.YAMLError as exc:
        raise ScenarioError(f'{path}: {yaml_files.yaml_problem(exc)}') from None
    except OSError as exc:
        raise ScenarioError(f'{path}: {exc.strerror or exc}') from None
    except UnicodeDecodeError:
        raise ScenarioError(f'{path}: not a text file') from None
    if raw is None:
        raise ScenarioError(f'{path}: empty, not a scenario')
    scenario = raw.get(SCENARIO_KEY) if isinstance(raw, dict) else None
    entry = scenario.get('ros__parameters') if isinstance(scenario, dict) else None
    if not isinstance(entry, dict) or not isinstance(entry.get('launch'), list):
        raise ScenarioError(f'{path}: no {SCENARIO_KEY}: ros__parameters: launch: list')
    nodes = []
    for line in entry['launch']:
        parts = str(line).split()
        if len(parts) != 3:
            raise ScenarioError(f'{path}: launch entry {line!r} is not "name package executable"')
        try:
            kind_of(parts[1], parts[2])
        except UnknownNodeKind as exc:
            raise ScenarioError(f'{path}: launch entry {line!r}: {exc}') from None
        nodes.append(NodeLaunch(*parts))
    scen = Scenario(path, str(entry.get('description', path.stem)), nodes, raw)
    scen.paper = str(entry.get('paper', ''))
    try:
        scen.set_namespace(str(entry.get('namespace', '')))
    except ScenarioError as exc:
        raise ScenarioError(f'{path}: {exc}') from None
    private_clock = entry.get('private_clock', False)
    if not isinstance(private_clock, bool):
        raise ScenarioError(f'{path}: private_clock must be true or false, got {private_clock!r}')
    scen.private_clock = private_clock
    try:
        scen.layout = check_layout(entry.get('layout', LAYOUTS[0]))
    except ScenarioError as exc:
        raise ScenarioError(f'{path}: {exc}') from None
    for line in entry.get('variants') or []:
        # "name NODE.NAME=VALUE ..." (a string list, so that rcl can read the file too)
        name, *overrides = str(line).split()
        scen.variants[name] = overrides
    scen.check_shared()
    for name in scen.variants:
        scen.variant(name)  # every override must name a node of the scenario
    return scen


def apply_params_file(scen: Scenario, path: str) -> None:
    """params_file entries as overrides of the scenario's nodes (ScenarioError if unusable).

    As a node reads a parameter file: an entry with a wildcard (`/**`, `/**/x_*`) gives each
    name to the nodes that declare it and no other; a name that no node it reaches declares
    is a typo, refused. A node's own entry may hold only names that node declares.
    """
    try:
        raw = yaml_files.read_yaml(path, ros_floats=True)
    except OSError as exc:
        raise ScenarioError(f'params_file {path}: {exc.strerror or exc}') from None
    except UnicodeDecodeError:
        raise ScenarioError(f'params_file {path}: not a text file') from None
    except yaml.YAMLError as exc:
        raise ScenarioError(f'params_file {path}: {yaml_files.yaml_problem(exc)}') from None
    if raw is None:
        raise ScenarioError(f'params_file {path}: empty: it sets no parameter')
    if not isinstance(raw, dict):
        raise ScenarioError(f'params_file {path}: not a ROS 2 parameter file')
    names = [n.name for n in scen.nodes]
    given = 0
    for key, entry in raw.items():
        values = (entry or {}).get('ros__parameters') if isinstance(entry, dict) else None
        where = f'params_file {path}: entry {key!r}'
        if not isinstance(values, dict):
            raise ScenarioError(f'{where} has no ros__parameters')
        pattern = str(key).removeprefix('/**').lstrip('/') or '*'
        shared = '*' in pattern
        targets = [n for n in names if fnmatch.fnmatchcase(n, pattern)]
        if not targets:
            raise ScenarioError(
                f'{where} names no node of scenario {scen.name} ({", ".join(names)})'
            )
        unknown = {}
        given += len(flatten(values))
        for param, value in flatten(values).items():
            declaring = [n for n in targets if scen.declares(n, param)]
            if not declaring:
                unknown[param] = value
            for name in declaring:
                scen.overrides.setdefault(name, {})[param] = value
        if unknown:
            known = {full for n in targets for full, _s in parameter_specs_of(scen.node(n))}
            if shared:
                them = 'them' if len(unknown) > 1 else 'it'
                message = unknown_parameters_message(
                    unknown, known, reason=f'no node of scenario {scen.name} declares {them}'
                )
            else:
                message = unknown_parameters_message(unknown, known, targets[0])
            raise ScenarioError(f'{where}: {message}')
    if not given:  # else the scenario would run as if no params_file had been given
        raise ScenarioError(f'params_file {path}: no ros__parameters values: it sets no parameter')
    scen.params_files.append(str(path))
