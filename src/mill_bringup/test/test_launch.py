"""The launch file without `launch`: what it starts (launch_plan) and that its adapter uses it.

The PyPI wheels ship neither `launch` nor `launch_ros`. What can be checked honestly without
them is checked here: every node and executable the launch names exists, the arguments are
the documented ones, bad arguments end in one line, and the launch file, run against
stand-in `launch` modules that only record what they are given, declares every argument
and hands every planned node to launch_ros. That launch itself accepts these actions was
checked by hand with launch built from source (docs/user-guide.md).
"""

from __future__ import annotations

import importlib.metadata
import importlib.util
import sys
import types
from pathlib import Path
from typing import Any

import pytest
import yaml
from mill_bringup.scenario import ScenarioError, parse_yaml

from mill_bringup import launch_plan

ROOT = Path(__file__).resolve().parents[3]
LAUNCH_FILE = ROOT / 'src' / 'mill_bringup' / 'launch' / 'scenario.launch.py'
USER_GUIDE = ROOT / 'docs' / 'user-guide.md'
SCENARIOS = sorted(p.stem for p in (ROOT / 'config').glob('*.yaml'))


def _console_scripts() -> dict[tuple[str, str], str]:
    out = {}
    for ep in importlib.metadata.entry_points(group='console_scripts'):
        package = ep.value.split('.')[0]
        out[(package, ep.name)] = ep.value
    return out


def documented_arguments() -> dict[str, str]:
    """The launch-argument table of docs/user-guide.md: name -> its default column."""
    text = USER_GUIDE.read_text()
    section = text[text.index('## With a full ROS 2 install') :]
    table = section[section.index('| argument | default | meaning |') :].split('\n\n')[0]
    rows = [line.split('|')[1:3] for line in table.splitlines()[2:] if line.startswith('|')]
    return {name.strip().strip('`'): default.strip() for name, default in rows}


def test_the_user_guide_lists_exactly_the_arguments_the_launch_declares() -> None:
    documented = documented_arguments()
    assert list(documented) == [a.name for a in launch_plan.ARGUMENTS]
    for a in launch_plan.ARGUMENTS:  # a default is quoted as it is; none is said in words
        assert (f'`{a.default}`' in documented[a.name]) is bool(a.default), a.name
        assert len(a.description) > 20


@pytest.mark.parametrize('name', SCENARIOS)
def test_every_planned_node_is_an_executable_of_its_package(name: str, tmp_path: Path) -> None:
    scripts = _console_scripts()
    plan = launch_plan.plan(name)
    path = launch_plan.write_parameters(plan, str(tmp_path))
    for node in plan.nodes:
        target = scripts.get((node.package, node.executable))
        assert target is not None, f'{node.package} has no executable {node.executable}'
        module = target.partition(':')[0]
        assert importlib.util.find_spec(module) is not None, module
        assert node.parameters == [str(path)] and node.namespace == '/'
        assert node.ros_arguments == ['--log-level', 'info']
    # Required: the node that clocks the job, and the job watch that ends the launch.
    required = sorted(n.executable for n in plan.nodes if n.required)
    clock = 'force_process_node' if name == 'rubio' else 'plant_node'
    assert required == sorted([clock, 'job_watch'])
    written = parse_yaml(path.read_text())
    views = {'/**/machine_view'} | (
        {'/**/robot_state_publisher'} if launch_plan.installed('robot_state_publisher') else set()
    )
    assert (
        set(written) == {'mill_scenario'} | {f'/**/{n.name}' for n in plan.scenario.nodes} | views
    )
    lines = written['mill_scenario']['ros__parameters']['launch']
    assert lines == [f'{n.name} {n.package} {n.executable}' for n in plan.scenario.nodes]


def test_namespace_params_file_timing_and_log_level(tmp_path: Path) -> None:
    params = tmp_path / 'gains.yaml'
    params.write_text(
        'x_controller:\n  ros__parameters:\n    pd.omega_c: 20.0\n'
        '/**:\n  ros__parameters:\n    sample_period: 0.001\n'
        '/**/plant:\n  ros__parameters:\n    substeps: 8\n'
    )
    plan = launch_plan.plan('slotting', 'machine2', str(params), 'realtime', 'warn')
    path = launch_plan.write_parameters(plan, str(tmp_path))
    written = yaml.safe_load(path.read_text())
    assert written['/**/x_controller']['ros__parameters']['pd.omega_c'] == 20.0
    assert written['/**/y_controller']['ros__parameters']['pd.omega_c'] == 12.0  # the file's
    assert written['/**/plant']['ros__parameters']['substeps'] == 8
    del written['mill_scenario']  # the nodes' names and kinds (for mill_container)
    for name in plan.scenario.nodes:
        entry = written[f'/**/{name.name}']
        # what run_scenario --timing realtime sets: no sim time, one sample of delay
        assert entry['ros__parameters']['timing'] == 'realtime'
        assert entry['ros__parameters']['use_sim_time'] is False
    for name in ('plant', 'x_controller', 'z_observer'):
        assert written[f'/**/{name}']['ros__parameters']['command_delay'] == 1
    for node in plan.nodes:
        assert node.namespace == '/machine2' and node.remappings == []
        assert node.ros_arguments == ['--log-level', 'warn']


def test_a_private_clock_scenario_remaps_clock(tmp_path: Path) -> None:
    text = (ROOT / 'config' / 'slotting.yaml').read_text()
    marker = '    description:'
    path = tmp_path / 'two.yaml'
    path.write_text(text.replace(marker, '    namespace: m2\n    private_clock: true\n' + marker))
    plan = launch_plan.plan(str(path))
    assert {n.namespace for n in plan.nodes} == {'/m2'}
    assert all(n.remappings == [('/clock', '/m2/clock')] for n in plan.nodes)
    # private_clock:=false overrides the scenario's
    plan = launch_plan.plan(str(path), private_clock='false')
    assert all(n.remappings == [] for n in plan.nodes)


@pytest.mark.parametrize('layout', ['processes', 'single'])
def test_private_clock_remaps_clock_into_the_namespace_for_every_process(layout: str) -> None:
    # Issue 34: two machines launched side by side in one domain each hear their own plant.
    plans = {
        m: launch_plan.plan('slotting', m, layout=layout, private_clock='true')
        for m in ('machine_a', 'machine_b')
    }
    for m, plan in plans.items():
        assert [n.remappings for n in plan.nodes] == [[('/clock', f'/{m}/clock')]] * len(plan.nodes)
        argv = launched_argv(plan.nodes[0])
        assert argv[-2:] == ['-r', f'/clock:=/{m}/clock']
    assert all(n.remappings == [] for n in launch_plan.plan('slotting', 'machine_a').nodes)


def test_a_realtime_machine_can_stay_up_after_its_job() -> None:
    # Issue 34: jog, home and MDI between jobs need the graph up once the job is done; the
    # launch ends with the job only while job_watch is in it.
    def names(**kwargs: str) -> set[str]:
        return {n.name for n in launch_plan.plan('slotting', timing='realtime', **kwargs).nodes}

    assert launch_plan.JOB_WATCH.name in names()
    stays = names(end_with_job='false')
    assert launch_plan.JOB_WATCH.name not in stays
    assert stays == names() - {launch_plan.JOB_WATCH.name}


@pytest.mark.parametrize(
    ('kwargs', 'message'),
    [
        ({'timing': 'fast'}, "timing must be one of lockstep, realtime, got 'fast'"),
        ({'log_level': 'loud'}, 'log_level must be one of debug'),
        ({'namespace': '9lives'}, "namespace '9lives' is not valid"),
        ({'scenario': 'nope'}, "no scenario 'nope'"),
        ({'params_file': 'missing.yaml'}, 'params_file missing.yaml: No such file'),
        ({'layout': 'pairs'}, "layout must be one of processes, per_axis, single, got 'pairs'"),
        ({'private_clock': 'yes'}, "private_clock must be true or false, got 'yes'"),
        ({'private_clock': 'true'}, r'a private clock needs a namespace \(namespace:=NAME\)'),
        ({'end_with_job': 'no'}, "end_with_job must be true or false, got 'no'"),
        ({'end_with_job': 'false'}, 'end_with_job:=false needs timing realtime'),
    ],
)
def test_bad_arguments_end_in_one_line(kwargs: dict[str, str], message: str) -> None:
    args = {'scenario': 'slotting', **kwargs}
    with pytest.raises(ScenarioError, match=message) as info:
        launch_plan.plan(**args)
    assert '\n' not in str(info.value)


def launched_argv(node: launch_plan.NodePlan) -> list[str]:
    """The command line launch_ros starts a Node action with: its executable, its
    arguments, then --ros-args: the ROS arguments, the node name (none for a container),
    the namespace, the parameter files and the remappings."""
    argv = [node.executable, *node.nodes, '--ros-args', *node.ros_arguments]
    if not node.nodes:
        argv += ['-r', f'__node:={node.name}']
    argv += ['-r', f'__ns:={node.namespace}']
    for f in node.parameters:
        argv += ['--params-file', f]
    for rule in node.remappings:
        argv += ['-r', f'{rule[0]}:={rule[1]}']
    return argv


@pytest.mark.parametrize(
    ('layout', 'containers'),
    [
        (
            'per_axis',
            [
                ['x_observer', 'x_controller'],
                ['y_observer', 'y_controller'],
                ['z_observer', 'z_controller'],
            ],
        ),
        ('single', [[n.name for n in launch_plan.load('slotting').nodes]]),
    ],
)
def test_each_container_of_a_layout_finds_its_nodes_in_the_launch_arguments(
    tmp_path: Path, layout: str, containers: list[list[str]]
) -> None:
    # Issue 34: mill_container ended with `no --params-file has a mill_scenario:
    # ros__parameters: launch: list naming the nodes` (rc 2, and 3 from the plant that waited
    # for them): the launch gave it the merged parameters only.
    from mill_bringup.container import makers
    from mill_common.param_sources import params_files

    plan = launch_plan.plan('slotting', 'machine_a', layout=layout)
    launch_plan.write_parameters(plan, str(tmp_path))
    started = [n for n in plan.nodes if n.nodes]
    assert [list(n.nodes) for n in started] == containers
    for node in started:
        argv = launched_argv(node)
        built = makers(list(node.nodes), params_files(argv))
        assert [name for name, _make in built] == list(node.nodes)


@pytest.mark.parametrize(
    ('layout', 'readers'), [('processes', None), ('per_axis', 1), ('single', 1)]
)
def test_the_plant_waits_for_the_readers_its_layout_gives_it(
    tmp_path: Path, layout: str, readers: int | None
) -> None:
    # An observer and its controller in one process count as one reader of the states: the
    # plant of a per_axis launch waited for 2 and ended after its startup timeout (rc 3).
    plan = launch_plan.plan('slotting', layout=layout)
    written = yaml.safe_load(launch_plan.write_parameters(plan, str(tmp_path)).read_text())
    assert written['/**/plant']['ros__parameters'].get('min_subscribers') == readers
    for axis_node in ('x_observer', 'x_controller'):  # no monitor to wait for: their defaults
        assert 'min_subscribers' not in written[f'/**/{axis_node}']['ros__parameters']
    assert plan.scenario.parameters('plant')['min_subscribers'] == (readers or 2)


def test_layouts_start_containers_that_keep_the_node_names(tmp_path: Path) -> None:
    scripts = _console_scripts()
    per_axis = launch_plan.plan('slotting', layout='per_axis')
    launch_plan.write_parameters(per_axis, str(tmp_path))
    containers = {n.name: n.nodes for n in per_axis.nodes if n.nodes}
    assert containers == {
        'x_axis': ('x_observer', 'x_controller'),
        'y_axis': ('y_observer', 'y_controller'),
        'z_axis': ('z_observer', 'z_controller'),
    }
    for node in per_axis.nodes:
        assert (node.package, node.executable) in scripts
        if node.nodes:
            assert (node.package, node.executable) == ('mill_bringup', 'mill_container')
            assert not node.required
    (single, watch, view, *_rsp) = launch_plan.plan('rubio', layout='single').nodes
    assert (view.name, view.required) == ('machine_view', False)
    assert single.nodes == ('force_process', 'trajectory', 'force_controller')
    assert single.required  # it holds the clock node
    assert (watch.name, watch.nodes, watch.required) == ('job_watch', (), True)


def test_params_file_must_name_nodes_of_the_scenario(tmp_path: Path) -> None:
    params = tmp_path / 'p.yaml'
    params.write_text('w_controller:\n  ros__parameters:\n    pd.omega_c: 20.0\n')
    with pytest.raises(ScenarioError, match="entry 'w_controller' names no node"):
        launch_plan.plan('slotting', params_file=str(params))
    params.write_text('x_controller:\n  ros__parameters:\n    pd.omega_c: -1.0\n')
    with pytest.raises(ScenarioError, match=r'pd\.omega_c'):  # checked before anything starts
        launch_plan.plan('slotting', params_file=str(params))


def test_a_params_file_that_sets_nothing_is_refused(tmp_path: Path):
    # else the scenario would run on its own values as if the file had been applied (the
    # kinds of such a file: mill_common's test_param_sources)
    params = tmp_path / 'p.yaml'
    params.write_text('x_controller:\n  ros__parameters: {}\n')
    with pytest.raises(ScenarioError) as info:
        launch_plan.plan('slotting', params_file=str(params))
    assert str(info.value) == (
        f'params_file {params}: no ros__parameters values: it sets no parameter'
    )


def test_a_shared_params_file_entry_reaches_only_the_nodes_that_declare_it(
    tmp_path: Path,
) -> None:
    params = tmp_path / 'shared.yaml'
    params.write_text(
        '/**:\n  ros__parameters:\n    gpi:\n      omega_o: 5.0\n    substeps: 8\n'
        '/**/x_*:\n  ros__parameters:\n    following_error_limit: 0.002\n'
    )
    plan = launch_plan.plan('slotting', params_file=str(params))
    written = launch_plan.write_parameters(plan, str(tmp_path))
    entries = {
        k.removeprefix('/**/'): v['ros__parameters']
        for k, v in parse_yaml(written.read_text()).items()
    }
    assert entries['plant']['substeps'] == 8 and 'gpi.omega_o' not in entries['plant']
    for axis in 'xyz':
        assert entries[f'{axis}_observer']['gpi.omega_o'] == 5.0
        assert 'gpi.omega_o' not in entries[f'{axis}_controller']
    assert entries['x_controller']['following_error_limit'] == 0.002
    assert entries['y_controller']['following_error_limit'] != 0.002


@pytest.mark.parametrize(
    ('text', 'message'),
    [
        (
            'x_controller:\n  ros__parameters:\n    pd.omega: 20.0\n',
            "entry 'x_controller': unknown parameter pd.omega=20.0 (did you mean pd.omega_c?): "
            'x_controller has no such parameter',
        ),
        (
            '/**:\n  ros__parameters:\n    gpi.omega_oo: 5.0\n',
            "entry '/**': unknown parameter gpi.omega_oo=5.0 (did you mean gpi.omega_o?): "
            'no node of scenario slotting declares it',
        ),
    ],
)
def test_an_unknown_name_names_the_params_file_and_its_entry(
    tmp_path: Path, text: str, message: str
) -> None:
    params = tmp_path / 'mine.yaml'
    params.write_text(text)
    with pytest.raises(ScenarioError) as info:
        launch_plan.plan('slotting', params_file=str(params))
    assert str(info.value) == f'params_file {params}: {message}'


def test_the_viewers_nodes_get_the_jobs_urdf_and_robot_state_publisher_only_if_found(
    tmp_path: Path,
) -> None:
    from xml.etree import ElementTree

    for found in (True, False):
        plan = launch_plan.plan('slotting', 'machine_a', found=lambda _package, f=found: f)
        path = launch_plan.write_parameters(plan, str(tmp_path))
        written = parse_yaml(path.read_text())
        names = [n.name for n in plan.nodes]
        assert names[-2:] == (
            ['machine_view', 'robot_state_publisher'] if found else ['job_watch', 'machine_view']
        )
        urdf = written['/**/machine_view']['ros__parameters']['robot_description']
        travel = plan.config.values('trajectory')  # type: ignore[union-attr]
        joints = ElementTree.fromstring(urdf).iter('joint')
        assert [float(j.find('limit').get('upper')) for j in joints] == travel['travel.max']
        if found:
            rsp = written['/**/robot_state_publisher']['ros__parameters']
            assert rsp == {'robot_description': urdf, 'frame_prefix': 'machine_a/'}
            assert plan.nodes[-1].package == 'robot_state_publisher'
            assert plan.notes == []
        else:
            assert '/**/robot_state_publisher' not in written
            assert plan.notes == [
                'robot_state_publisher is not installed: no /tf of the machine (the URDF is '
                'on /machine_a/robot_description)'
            ]
        assert not any(
            n.required for n in plan.nodes if n.name in names[-2:] and n.name != 'job_watch'
        )


def test_exit_codes_as_a_shell_reports_them() -> None:
    assert [launch_plan.exit_code(c) for c in (0, 3, -2, -9, 300)] == [0, 3, 130, 137, 255]


# -- the launch file against stand-ins that record what they are given ---------------------


class _Recorded:
    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self.args, self.kwargs = args, kwargs


def _stand_ins(values: dict[str, str]) -> dict[str, types.ModuleType]:
    def module(name: str, **members: Any) -> types.ModuleType:
        mod = types.ModuleType(name)
        mod.__dict__.update(members)
        return mod

    class LaunchConfiguration:
        def __init__(self, name: str) -> None:
            self.name = name

        def perform(self, _context: Any) -> str:
            return values[self.name]

    kinds = {
        k: type(k, (_Recorded,), {})
        for k in (
            'LaunchDescription',
            'DeclareLaunchArgument',
            'OpaqueFunction',
            'RegisterEventHandler',
            'Shutdown',
            'LogInfo',
            'OnProcessExit',
            'Node',
        )
    }
    actions = (
        'DeclareLaunchArgument',
        'LogInfo',
        'OpaqueFunction',
        'RegisterEventHandler',
        'Shutdown',
    )
    return {
        'launch': module('launch', LaunchDescription=kinds['LaunchDescription']),
        'launch.actions': module('launch.actions', **{k: kinds[k] for k in actions}),
        'launch.event_handlers': module(
            'launch.event_handlers', OnProcessExit=kinds['OnProcessExit']
        ),
        'launch.substitutions': module(
            'launch.substitutions', LaunchConfiguration=LaunchConfiguration
        ),
        'launch_ros': module('launch_ros'),
        'launch_ros.actions': module('launch_ros.actions', Node=kinds['Node']),
    }


def test_launch_file_declares_the_arguments_and_starts_the_plan(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    values = {a.name: a.default for a in launch_plan.ARGUMENTS}
    values.update(namespace='machine2', log_level='warn', private_clock='true')
    for name, mod in _stand_ins(values).items():
        monkeypatch.setitem(sys.modules, name, mod)
    monkeypatch.setattr('tempfile.tempdir', str(tmp_path))
    spec = importlib.util.spec_from_file_location('scenario_launch', LAUNCH_FILE)
    launch_file = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(launch_file)

    description = launch_file.generate_launch_description()
    entities = description.args[0]
    declared = {
        e.args[0]: e.kwargs for e in entities if type(e).__name__ == 'DeclareLaunchArgument'
    }
    assert list(declared) == [a.name for a in launch_plan.ARGUMENTS]
    for a in launch_plan.ARGUMENTS:
        assert declared[a.name] == {'default_value': a.default, 'description': a.description}
    (opaque,) = [e for e in entities if type(e).__name__ == 'OpaqueFunction']

    actions = opaque.kwargs['function'](object())
    nodes = [a.kwargs for a in actions if type(a).__name__ == 'Node']
    plan = launch_plan.plan('slotting', 'machine2', log_level='warn', private_clock='true')
    assert [(n['package'], n['executable'], n['name']) for n in nodes] == [
        (p.package, p.executable, p.name) for p in plan.nodes
    ]
    assert all(n['arguments'] == [] for n in nodes)
    assert all(n['namespace'] == '/machine2' for n in nodes)
    assert all(n['remappings'] == [('/clock', '/machine2/clock')] for n in nodes)
    assert all(n['ros_arguments'] == ['--log-level', 'warn'] for n in nodes)
    assert all(Path(n['parameters'][0]).is_file() for n in nodes)
    notes = [a.kwargs['msg'] for a in actions if type(a).__name__ == 'LogInfo']
    assert notes == plan.notes  # robot_state_publisher not installed here: one INFO line
    handlers = [a.args[0] for a in actions if type(a).__name__ == 'RegisterEventHandler']
    watched = sorted(h.kwargs['target_action'].kwargs['name'] for h in handlers)
    assert watched == ['job_watch', 'plant']

    # The plant ending by itself with code 3 ends the launch and sets the exit code.
    class Event:
        returncode = 3

    class Context:
        is_shutdown = False

    plant = next(h for h in handlers if h.kwargs['target_action'].kwargs['name'] == 'plant')
    monkeypatch.setattr('atexit.register', lambda f: None)
    (shutdown,) = plant.kwargs['on_exit'](Event(), Context())
    assert type(shutdown).__name__ == 'Shutdown'
    assert launch_file._exit['code'] == 3


def test_launch_file_starts_a_container_without_a_node_name(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    values = {a.name: a.default for a in launch_plan.ARGUMENTS}
    values.update(layout='single')
    for name, mod in _stand_ins(values).items():
        monkeypatch.setitem(sys.modules, name, mod)
    monkeypatch.setattr('tempfile.tempdir', str(tmp_path))
    spec = importlib.util.spec_from_file_location('scenario_launch', LAUNCH_FILE)
    launch_file = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(launch_file)
    entities = launch_file.generate_launch_description().args[0]
    (opaque,) = [e for e in entities if type(e).__name__ == 'OpaqueFunction']
    actions = opaque.kwargs['function'](object())
    nodes = [a.kwargs for a in actions if type(a).__name__ == 'Node']
    # `name` would become a global __node remap and rename every node of the container.
    assert [(n['executable'], n['name'], n['arguments']) for n in nodes] == [
        ('mill_container', None, [n.name for n in launch_plan.load('slotting').nodes]),
        ('job_watch', 'job_watch', []),
        ('machine_view', 'machine_view', []),
    ]
    handlers = [a.args[0] for a in actions if type(a).__name__ == 'RegisterEventHandler']
    assert len(handlers) == 2  # the container holds the plant: required, as job_watch
