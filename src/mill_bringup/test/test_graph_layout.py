"""How the graph starts the processes of a layout and names them (no process is started)."""

from __future__ import annotations

import sys
from pathlib import Path

from mill_bringup.graph import Graph
from mill_bringup.layout import processes
from mill_bringup.scenario import load


def test_a_container_gets_its_nodes_and_the_arguments_a_node_alone_gets(tmp_path: Path) -> None:
    scen = load('slotting')
    scen.set_namespace('machine2')
    graph = Graph(scen, tmp_path, {})
    by_name = {p.name: p for p in processes(scen, 'per_axis')}
    alone = graph.command(by_name['plant'])
    packed = graph.command(by_name['x_axis'])
    assert alone[:3] == [sys.executable, '-m', 'mill_plant.plant_node']
    assert alone[3:6] == ['--ros-args', '-r', '__node:=plant']
    assert packed[:6] == [
        sys.executable,
        '-m',
        'mill_bringup.container',
        'x_observer',
        'x_controller',
        '--ros-args',
    ]
    # Namespace and parameter files: the same for both.
    assert alone[6:] == packed[6:]
    assert packed[6:8] == ['-r', '__ns:=/machine2']
    assert packed[-4:] == [
        '--params-file',
        str(scen.path),
        '--params-file',
        str(tmp_path / 'parameters.yaml'),
    ]


def test_messages_name_a_container_with_its_nodes(tmp_path: Path) -> None:
    scen = load('slotting')
    graph = Graph(scen, tmp_path, {})
    graph.processes = {p.name: p for p in processes(scen, 'per_axis')}
    assert graph.what('plant') == 'node plant'
    assert graph.what('y_axis') == 'process y_axis (nodes y_observer, y_controller)'
    assert graph.node_names() == {n.name for n in scen.nodes}
