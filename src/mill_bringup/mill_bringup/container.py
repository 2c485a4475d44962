"""Several nodes of a scenario in one process, one ROS context and one executor.

    mill_container x_observer x_controller --ros-args --params-file config/slotting.yaml
    python -m mill_bringup.container NODE [NODE ...] --ros-args [-r __ns:=NS] \
        --params-file SCENARIO [--params-file MORE ...] [-r RULE ...] [--log-level LEVEL]

As a ROS 2 component container composes nodes: each node is created with its own
`-r __node:=NAME`, so it keeps the name the scenario gives it, and with it its entries of
the parameter files (`/**/NAME`), its topics and its services. The `--ros-args` of the
container (namespace, remappings, parameter files, `-p`, log level) apply to every node in
it, as they would to each node started alone. Which class each NAME is comes from the
`mill_scenario: launch:` entry (`NAME PACKAGE EXECUTABLE`) of the parameter files given,
and the node catalogue (mill_bringup.catalogue) says how to build it.

A node that ends by itself (a lockstep timeout, a configuration error) ends the container
with its exit code, its message prefixed by the node's name; Ctrl-C or SIGTERM end them all.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import yaml
from mill_common.yaml_files import YamlRefused, read_yaml

from mill_bringup.catalogue import KINDS, UnknownNodeKind, kind_of
from mill_bringup.scenario import SCENARIO_KEY

if TYPE_CHECKING:
    from rclpy.node import Node

PROG = 'mill_container'


USAGE = f"""usage: {PROG} NODE [NODE ...] --ros-args --params-file SCENARIO [ROS ARGUMENTS]

Run several nodes of a scenario in one process and one executor (a deployment choice:
each node keeps its name, parameters and topics, as when it runs in its own process).
NODE names an entry `NAME PACKAGE EXECUTABLE` of the `{SCENARIO_KEY}: launch:` list of a
--params-file given. The --ros-args (namespace, remappings, parameter files, -p, log level)
apply to every node. The first node to end by itself ends the container with its exit code.

Messages between the nodes of the container are handed over in the process (they still go
to DDS for every other reader); MILL_INTRA_PROCESS=0 sends them through DDS only.

executables that can run in a container:
""" + '\n'.join(f'  {k.package} {k.executable}' for k in KINDS)


class ContainerError(ValueError):
    """A container that cannot start; str() says why in one line."""


def scenario_launch(files: Sequence[str]) -> dict[str, tuple[str, str]]:
    """NAME -> (package, executable) from the `mill_scenario: launch:` entry of the files."""
    for path in files:
        try:
            raw = read_yaml(path)
        except YamlRefused as exc:  # read by none of the container's nodes either
            raise ContainerError(f'--params-file {path}: {exc}') from None
        except (OSError, UnicodeDecodeError, yaml.YAMLError):
            continue  # rcl says what is wrong with the file
        entry = raw.get(SCENARIO_KEY) if isinstance(raw, dict) else None
        params = entry.get('ros__parameters') if isinstance(entry, dict) else None
        lines = params.get('launch') if isinstance(params, dict) else None
        if not isinstance(lines, list):
            continue
        out = {}
        for line in lines:
            parts = str(line).split()
            if len(parts) != 3:
                raise ContainerError(
                    f'{path}: launch entry {line!r} is not "name package executable"'
                )
            out[parts[0]] = (parts[1], parts[2])
        return out
    raise ContainerError(
        f'no --params-file has a {SCENARIO_KEY}: ros__parameters: launch: list naming the nodes'
    )


def makers(names: Sequence[str], files: Sequence[str]) -> list[tuple[str, Callable[[], Node]]]:
    """(name, factory) of each node: built with its own name, the container's ROS arguments."""
    if not names:
        raise ContainerError('no node named; give NODE ... before --ros-args')
    doubled = sorted({n for n in names if names.count(n) > 1})
    if doubled:
        raise ContainerError(f'node {doubled[0]} named twice')
    launch = scenario_launch(files)
    out: list[tuple[str, Callable[[], Node]]] = []
    for name in names:
        if name not in launch:
            raise ContainerError(f'the scenario has no node {name!r} (has: {", ".join(launch)})')
        try:
            kind = kind_of(*launch[name])
        except UnknownNodeKind as exc:
            raise ContainerError(str(exc)) from None
        out.append((name, _maker(kind.build(), name)))
    return out


def _maker(build: Callable[..., Node], name: str) -> Callable[[], Node]:
    """A factory of node `name` built by `build` with its own node name."""

    def make() -> Node:
        options: dict[str, Any] = {'cli_args': ['--ros-args', '-r', f'__node:={name}']}
        return build(**options)

    return make


def main(argv: list[str] | None = None) -> int:
    from mill_common.node_main import run_nodes
    from mill_common.param_sources import params_files

    own_process = argv is None
    argv = list(sys.argv if argv is None else argv)
    args = argv[1:]
    user = args[: args.index('--ros-args')] if '--ros-args' in args else args
    if '-h' in user or '--help' in user:
        print(USAGE)
        return 0
    try:
        nodes = makers(user, params_files(argv))
    except ContainerError as exc:
        print(f'{PROG}: error: {exc}', file=sys.stderr)
        return 2
    if len(nodes) > 1:
        from mill_common.intra_process import bus

        bus().enable()  # messages between these nodes skip DDS (mill_common.intra_process)
    return run_nodes(nodes, PROG, argv, own_process, connect_servo_cycles)


def connect_servo_cycles(nodes: Sequence[Any]) -> None:
    """The observer and the controller of one axis in this process run one servo cycle:
    the observer hands each estimated sample to the controller at once, which sends its
    command before the estimate goes out (mill_observers.observer_node, servo)."""
    observers = {n.axis: n for n in nodes if hasattr(n, 'servo')}
    for controller in (n for n in nodes if hasattr(n, 'attach')):
        observer = observers.get(controller.axis)
        if observer is None or observer.get_namespace() != controller.get_namespace():
            continue
        wanted = controller.params.values['observer_node'] or f'{controller.axis}_observer'
        owner = observer.params.values['controller_node'] or f'{observer.axis}_controller'
        if wanted != observer.get_name() or owner != controller.get_name():
            continue  # they take another node's messages: no cycle of their own
        servo = controller.attach(observer.params.values['plant_node'], observer.commanded)
        if servo is not None:
            observer.serve(servo)


if __name__ == '__main__':
    raise SystemExit(main())
