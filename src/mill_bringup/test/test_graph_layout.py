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


def test_run_scenario_view_starts_machine_view_beside_the_graph_with_the_jobs_urdf(
    tmp_path: Path,
) -> None:
    from xml.etree import ElementTree

    from mill_bringup.job_config import build
    from mill_bringup.machine_model import VIEW_MODULE, VIEW_NODE, view_parameters
    from mill_bringup.runner.cli import parser, run_options

    assert not run_options(parser().parse_args(['slotting']), None).view  # off by default
    assert run_options(parser().parse_args(['slotting', '--view']), None).view
    scen = load('slotting')
    scen.set_namespace('machine2')
    scen.private_clock = True
    cmd = Graph(scen, tmp_path, {}).beside_command(VIEW_NODE, VIEW_MODULE)
    assert cmd == [
        *(sys.executable, '-m', 'mill_bringup.machine_view', '--ros-args'),
        *('-r', '__node:=machine_view', '-r', '__ns:=/machine2', '-r', '/clock:=/machine2/clock'),
        *('--params-file', str(tmp_path / 'machine_view.yaml')),
    ]
    # its URDF is the job's machine: the travel the job's trajectory holds
    scen.add_override('trajectory.travel.max=[0.25, 0.5, 0.125]')
    ((key, entry),) = view_parameters(build(scen)).items()
    assert key == '/**/machine_view'
    urdf = ElementTree.fromstring(entry['ros__parameters']['robot_description'])
    limits = [j.find('limit') for j in urdf.iter('joint')]
    uppers = [float(limit.get('upper', 'nan')) for limit in limits if limit is not None]
    assert uppers == [0.25, 0.5, 0.125]
