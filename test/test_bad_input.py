"""Bad parameters: refused at start-up with one line naming them, refused at run time with a
reason naming them while the node keeps its previous values and keeps running.

Start-up cases pass plain `-p NAME:=VALUE` without the scenario file: a node-specific
entry of a params file (`x_controller: ros__parameters: ...`) takes precedence over a plain
`-p` (rcl stores `-p` under `/**`), so with the scenario file the bad value would not even
reach the node. `-p NODE:NAME:=VALUE` is the form that overrides a file.
"""

from __future__ import annotations

import math

import pytest
from mill_common.ros import DATA_QOS, joint_state
from mill_common.signals import FopdtEstimate
from sensor_msgs.msg import JointState

from mill_common import topics
from test.conftest import ParameterClient, ros_node, run_scenario, wait_until

PLANT = ('mill_plant.plant_node', 'plant_node', 'plant')
CONTROLLER = ('mill_controllers.axis_controller_node', 'axis_controller_node', 'x_controller')
OBSERVER = ('mill_observers.observer_node', 'observer_node', 'x_observer')

# (node, -p argument, parameter the error must name)
BAD_STARTUP = [
    (CONTROLLER, 'controller:=bogus', 'controller'),
    (CONTROLLER, 'pd.omega_c:=-5.0', 'pd.omega_c'),
    (CONTROLLER, 'pd.zeta_c:=0.0', 'pd.zeta_c'),
    (CONTROLLER, 'pd.zeta_c:=-0.7', 'pd.zeta_c'),
    (CONTROLLER, 'axis:=w', 'axis'),
    (OBSERVER, 'gpi.omega_o:=0.0', 'gpi.omega_o'),
    (OBSERVER, 'gpi.omega_o:=-700.0', 'gpi.omega_o'),
    (OBSERVER, 'gpi.zeta_o:=0.0', 'gpi.zeta_o'),
    (OBSERVER, 'gpi.zeta_o:=-0.5', 'gpi.zeta_o'),
    (OBSERVER, 'axis:=w', 'axis'),
    (PLANT, 'axes:=["x","w"]', 'axes'),
    (PLANT, 'mass:=[17.551, 0.0, 22.505]', 'mass'),
    (PLANT, 'mass:=[17.551, 23.896, -1.0]', 'mass'),
]


@pytest.mark.system
@pytest.mark.parametrize(
    ('node', 'arg', 'param'), BAD_STARTUP, ids=[f'{n[1]}-{a}' for n, a, _ in BAD_STARTUP]
)
def test_bad_startup_parameter_exits_2_with_one_line(start_node, node, arg, param) -> None:
    module, executable, name = node
    proc = start_node(module, name, '-p', arg, params_file=False)
    code, _out, err = proc.wait(timeout=60)
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2, err
    assert len(lines) == 1, err
    assert lines[0].startswith(f'{executable}: error: invalid parameter {param}='), lines[0]


def _assert_rejected(result, name: str) -> None:
    assert not result.successful, f'{name}: change accepted'
    assert name in result.reason, result.reason


@pytest.mark.system
def test_controller_rejects_bad_changes_at_run_time(start_node) -> None:
    controller = start_node(CONTROLLER[0], 'x_controller')
    with ros_node('param_tester') as (node, executor):
        params = ParameterClient(node, executor, 'x_controller')
        before = params.get('pd.omega_c', 'controller', 'axis')
        assert before == {'pd.omega_c': 12.0, 'controller': 'adrc', 'axis': 'x'}

        _assert_rejected(params.set('pd.omega_c', -1.0), 'pd.omega_c')
        _assert_rejected(params.set('controller', 'bogus'), 'controller')
        _assert_rejected(params.set('axis', 'y'), 'axis')  # read-only
        undeclared = params.set('pd.omega', 20.0)
        _assert_rejected(undeclared, 'pd.omega=20.0 (did you mean pd.omega_c?)')
        # Issue 37: a gain of a law that does not run, which it cannot be built with.
        overflow = params.set('gpi.omega_n', 1e300)
        _assert_rejected(overflow, 'gpi.omega_n=1e+300: gpi (not the running law): OverflowError')
        assert params.get('pd.omega_c', 'controller', 'axis') == before
        assert params.get('gpi.omega_n') == {'gpi.omega_n': 80.0}
        assert controller.alive()

        assert params.set('pd.omega_c', 20.0).successful
        assert params.get('pd.omega_c', 'controller', 'axis') == {**before, 'pd.omega_c': 20.0}
        assert params.get('pd.zeta_c') == {'pd.zeta_c': 0.7071}  # still answering
        # `ros2 param set ... 25` sends an integer: stored as the double it means.
        assert params.set('pd.omega_c', 25).successful
        value = params.get('pd.omega_c')['pd.omega_c']
        assert isinstance(value, float) and value == 25.0
    assert controller.alive()


@pytest.mark.system
def test_observer_rejects_bad_changes_at_run_time(start_node) -> None:
    observer = start_node(OBSERVER[0], 'x_observer')
    with ros_node('param_tester') as (node, executor):
        params = ParameterClient(node, executor, 'x_observer')
        before = params.get('gpi.zeta_o', 'gpi.omega_o', 'observer')
        assert before == {'gpi.zeta_o': 0.7071, 'gpi.omega_o': 700.0, 'observer': 'gpi'}

        _assert_rejected(params.set('gpi.zeta_o', 0.0), 'gpi.zeta_o')
        _assert_rejected(params.set('observer', 'bogus'), 'observer')
        assert params.get('gpi.zeta_o', 'gpi.omega_o', 'observer') == before
        assert params.set('gpi.zeta_o', 0.9).successful
        assert params.get('gpi.zeta_o') == {'gpi.zeta_o': 0.9}
    assert observer.alive()


@pytest.mark.system
def test_switch_to_a_law_needing_a_model_waits_for_one(start_node) -> None:
    """adaptive_pi with model_source observer designs with the rls observer's estimate: a
    switch to it is refused with the reason while no estimate has arrived, accepted after."""

    controller = start_node(
        CONTROLLER[0], 'x_controller', '-p', 'x_controller:controller:=machine_pi'
    )
    # the observer the controller trusts (observer_node: x_observer), as the graph names it
    with ros_node('x_observer') as (node, executor):
        params = ParameterClient(node, executor, 'x_controller')
        assert params.set('adaptive_pi.model_source', 'observer').successful  # not running
        refused = params.set('controller', 'adaptive_pi')
        assert not refused.successful
        assert topics.observer_state('x') in refused.reason, refused.reason
        assert params.get('controller') == {'controller': 'machine_pi'}
        assert controller.alive()

        pub = node.create_publisher(JointState, topics.observer_state('x'), DATA_QOS)
        assert wait_until(lambda: pub.get_subscription_count() > 0, 30)
        status = FopdtEstimate(29.0, 2.0, 1.25e-4, 0.5, 500).as_status()
        # From the observer the controller trusts (observer_node: x_observer by default).
        pub.publish(joint_state(0, tuple(status), tuple(status.values()), sender='x_observer'))

        def accepted() -> bool:
            executor.spin_once(timeout_sec=0.05)
            return params.set('controller', 'adaptive_pi').successful

        assert wait_until(accepted, 30)
        assert params.get('controller') == {'controller': 'adaptive_pi'}
    assert controller.alive()


# -- start-up input: types, unknown names, parameter files -----------------------------------

MIXED_LIST = 'x_controller:\n  ros__parameters:\n    pd.omega_c: [1, 2.5]\n'

# (node, ros args (FILE = the params file written from `text`), params file text, the line)
BAD_INPUT = [
    (
        CONTROLLER,
        ['-p', 'pd.omega_c:=abc'],
        None,
        "axis_controller_node: error: invalid parameter pd.omega_c='abc': "
        'must be of type double (a floating-point number), got string',
    ),
    (
        PLANT,
        ['-p', 'substeps:=2.5'],
        None,
        'plant_node: error: invalid parameter substeps=2.5: '
        'must be of type integer (a whole number), got double',
    ),
    (
        CONTROLLER,
        ['-p', 'pd.omega:=20.0'],
        None,
        'axis_controller_node: error: unknown parameter pd.omega=20.0 (did you mean pd.omega_c?): '
        '/x_controller has no such parameter',
    ),
    (
        OBSERVER,
        ['--params-file', 'FILE'],
        'x_observer:\n  ros__parameters:\n    gpi:\n      omega: 700.0\n',
        'observer_node: error: unknown parameter gpi.omega=700.0 (did you mean gpi.omega_o?): '
        '/x_observer has no such parameter',
    ),
    (
        CONTROLLER,
        ['--params-file', '/nonexistent/params.yaml'],
        None,
        'axis_controller_node: error: --params-file /nonexistent/params.yaml: no such file',
    ),
    (
        CONTROLLER,
        ['--params-file', 'FILE'],
        'x_controller:\n  ros__parameters:\n    pd.omega_c: [1.0, 2.0\n',
        "axis_controller_node: error: --params-file FILE: not valid YAML (expected ',' or ']', "
        "but got '<stream end>' at line 4, column 1)",
    ),
    (
        CONTROLLER,
        ['--params-file', 'FILE'],
        MIXED_LIST,
        'axis_controller_node: error: --params-file FILE: sequence should be of same type. '
        "Value type 'double' do not belong at line_num 3",
    ),
    (CONTROLLER, ['-p', 'omega'], None, 'axis_controller_node: error: -p omega: not NAME:=VALUE'),
    # A file that sets nothing for the node: it would run on its defaults (a 5 mm
    # following-error limit where the scenario says 1 mm).
    (
        CONTROLLER,
        ['--params-file', 'FILE'],
        '',
        'axis_controller_node: error: --params-file FILE: empty: it sets no parameter',
    ),
    (
        CONTROLLER,
        ['--params-file', 'FILE'],
        'y_controller:\n  ros__parameters:\n    following_error_limit: 0.001\n',
        'axis_controller_node: error: --params-file FILE: nothing in it is for /x_controller '
        '(its entries: /y_controller)',
    ),
]


@pytest.mark.system
@pytest.mark.parametrize(
    ('node', 'args', 'text', 'line'),
    BAD_INPUT,
    ids=[
        *('wrong-type', 'wrong-int', 'unknown-p', 'unknown-file', 'missing', 'yaml', 'rcl'),
        *('rule', 'empty-file', 'file-for-another-node'),
    ],
)
def test_bad_startup_input_exits_2_with_one_line(start_node, tmp_path, node, args, text, line):
    module, _executable, name = node
    path = tmp_path / 'params.yaml'
    if text is not None:
        path.write_text(text)
    args = [str(path) if a == 'FILE' else a for a in args]
    proc = start_node(module, name, *args, params_file=False)
    code, _out, err = proc.wait(timeout=60)
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2, err
    assert lines == [line.replace('FILE', str(path))], err


@pytest.mark.system
def test_shared_entries_a_node_does_not_declare_are_ignored(start_node, tmp_path) -> None:
    """/** is for every node the file starts: the controller ignores the force process's
    parameter there, but takes what it declares (sample_period)."""
    path = tmp_path / 'params.yaml'
    path.write_text(
        '/**:\n  ros__parameters:\n    sample_period: 0.002\n    force_process.flutes: 4\n'
        'x_controller:\n  ros__parameters:\n    pd:\n      omega_c: 20\n'
    )
    controller = start_node(
        CONTROLLER[0], 'x_controller', '--params-file', str(path), params_file=False
    )
    with ros_node('param_tester') as (node, executor):
        params = ParameterClient(node, executor, 'x_controller')
        values = params.get('sample_period', 'pd.omega_c')
        assert values == {'sample_period': 0.002, 'pd.omega_c': 20.0}
        assert isinstance(values['pd.omega_c'], float)  # 20 in the file: the declared double
    assert controller.alive()


@pytest.mark.system
def test_descriptors_show_types_ranges_and_constraints(start_node) -> None:
    from rcl_interfaces.msg import ParameterType

    start_node(CONTROLLER[0], 'x_controller')
    with ros_node('param_tester') as (node, executor):
        params = ParameterClient(node, executor, 'x_controller')
        d = params.describe(
            'pd.omega_c', 'controller', 'axis', 'adaptive_pi.input_taps', 'sample_period'
        )
        omega = d['pd.omega_c']
        assert omega.type == ParameterType.PARAMETER_DOUBLE and not omega.dynamic_typing
        assert omega.description.startswith('natural frequency ω_c')
        assert omega.additional_constraints == '>= 0'  # 0: the tuning rule's
        (r,) = omega.floating_point_range
        assert (r.from_value, r.to_value, r.step) == (0.0, math.inf, 0.0)
        law = d['controller']
        assert law.type == ParameterType.PARAMETER_STRING
        assert (
            law.additional_constraints.startswith('one of: ')
            and 'adrc' in law.additional_constraints
        )
        assert d['axis'].read_only and d['axis'].additional_constraints == 'one of: x, y, z'
        (taps,) = d['adaptive_pi.input_taps'].integer_range
        assert d['adaptive_pi.input_taps'].type == ParameterType.PARAMETER_INTEGER
        assert (taps.from_value, taps.to_value, taps.step) == (1, 32, 1)  # issue 37: bounded
        (period,) = d['sample_period'].floating_point_range
        assert (period.from_value, period.to_value) == (1e-6, 1.0)

        # At run time ROS refuses a value of another type or outside the range by itself.
        refused = params.set('pd.omega_c', 'abc')
        assert not refused.successful and 'type' in refused.reason.lower()
        refused = params.set('pd.omega_c', -1.0)
        assert not refused.successful and 'pd.omega_c' in refused.reason
        assert params.get('pd.omega_c') == {'pd.omega_c': 12.0}


@pytest.mark.system
def test_run_scenario_refuses_an_unknown_override_before_anything_starts(ros_env, tmp_path):
    run_dir = tmp_path / 'run'
    proc = run_scenario(
        ros_env,
        *('slotting', '-p', 'x_controller.pd.omega=3.0', '--output', str(run_dir)),
        timeout=120,
    )
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == 2 and lines == [
        "run_scenario: error: override 'x_controller.pd.omega=3.0': unknown parameter "
        'pd.omega=3.0 (did you mean pd.omega_c?): x_controller has no such parameter'
    ], proc.stderr
    assert not run_dir.exists()  # nothing was started
