"""Where a node's parameters come from: -p arguments and parameter files, as rcl reads them."""

from __future__ import annotations

from pathlib import Path

import pytest
from mill_common.param_sources import (
    flatten,
    parameter_rule_problem,
    parameter_sources,
    params_file_miss,
    params_file_problem,
    params_files,
    rcl_error_message,
    ros_arguments,
)

SCENARIO = """
/**:
  ros__parameters:
    use_sim_time: true
    sample_period: 0.001
    force_process.flutes: 4
x_controller:
  ros__parameters:
    pd:
      omega_c: 12.0
/y_controller:
  ros__parameters:
    pd.zeta_c: 0.7
/**/x_controller:
  ros__parameters:
    blend_time: 0.1
/mill:
  x_controller:
    ros__parameters:
      input_gain: 1.0
"""


def test_only_the_ros_args_sections_count() -> None:
    argv = ['node', '-p', 'a:=1', '--ros-args', '-p', 'b:=2', '--', '-p', 'c:=3', '--ros-args']
    assert ros_arguments(argv) == ['-p', 'b:=2']
    argv = ['n', '--ros-args', '--params-file', 'f1', '-r', '__node:=x', '--params-file', 'f2']
    assert params_files(argv) == ['f1', 'f2']


def test_nested_parameters_are_flattened_as_rcl_does() -> None:
    assert flatten({'pd': {'omega_c': 12.0, 'zeta_c': 0.7}, 'axis': 'x'}) == {
        'pd.omega_c': 12.0,
        'pd.zeta_c': 0.7,
        'axis': 'x',
    }


def test_direct_and_shared_names(tmp_path: Path) -> None:
    f = tmp_path / 'scenario.yaml'
    f.write_text(SCENARIO)
    argv = [
        *('x', '--ros-args', '-r', '__node:=x_controller', '--params-file', str(f)),
        *('-p', 'controller:=pd', '-p', 'y_controller:gpi.pole:=5.0'),
        *('-p', 'x_controller:pd.torque_limit:=3.0', '-p', '/x_controller:axis:=x'),
    ]
    sources = parameter_sources(argv, 'x_controller', '/x_controller')
    # -p for this node (plain, or NODE:NAME naming it), and its own file entry
    assert sources.direct == {'controller', 'pd.torque_limit', 'axis', 'pd.omega_c'}
    # entries under keys with a wildcard are for every node the file starts
    assert sources.shared == {
        'use_sim_time',
        'sample_period',
        'force_process.flutes',
        'blend_time',
    }
    assert sources.files == [str(f)]
    # another node: its own entry, and the namespaced entry matches only inside /mill
    other = parameter_sources(argv, 'y_controller', '/y_controller')
    assert other.direct == {'controller', 'gpi.pole', 'pd.zeta_c'}
    inside = parameter_sources(argv, 'x_controller', '/mill/x_controller')
    assert 'input_gain' in inside.direct


def test_params_file_problems_in_one_line(tmp_path: Path) -> None:
    assert params_file_problem(str(tmp_path / 'missing.yaml')) == 'no such file'
    assert params_file_problem(str(tmp_path)) == 'is a directory, not a parameter file'
    bad = tmp_path / 'bad.yaml'
    bad.write_text('a:\n  ros__parameters:\n    x: [1, 2\n')
    problem = params_file_problem(str(bad))
    assert problem is not None and problem.startswith('not valid YAML (')
    assert 'line 4' in problem and '\n' not in problem
    good = tmp_path / 'good.yaml'
    good.write_text(SCENARIO)
    assert params_file_problem(str(good)) is None


@pytest.mark.parametrize(
    ('text', 'problem'),
    [
        ('', 'empty: it sets no parameter'),
        ('# gains for later\n', 'empty: it sets no parameter'),
        ('{}\n', 'no ros__parameters values: it sets no parameter'),
        ('hello\n', 'no ros__parameters values: it sets no parameter'),
        (
            'x_controller:\n  ros__parameters: {}\n',
            'no ros__parameters values: it sets no parameter',
        ),
    ],
)
def test_a_params_file_that_sets_nothing_is_a_problem(tmp_path: Path, text: str, problem: str):
    f = tmp_path / 'p.yaml'
    f.write_text(text)
    assert params_file_problem(str(f)) == problem


def test_a_params_file_that_holds_nothing_for_the_process_is_named(tmp_path: Path) -> None:
    f = tmp_path / 'p.yaml'
    f.write_text(SCENARIO)
    assert params_file_miss(str(f), ['/x_controller']) is None
    assert params_file_miss(str(f), ['/plant']) is None  # the /** entry
    f.write_text(
        'y_controller:\n  ros__parameters:\n    pd.omega_c: 20.0\n'
        '/**/z_observer:\n  ros__parameters:\n    gpi.omega_o: 500.0\n'
        'x_controller:\n  ros__parameters: {}\n'  # an entry without values gives nothing
    )
    assert params_file_miss(str(f), ['/x_controller']) == (
        'nothing in it is for /x_controller (its entries: /y_controller, /**/z_observer)'
    )
    # a file given to a container: it must hold something for one of its nodes
    assert params_file_miss(str(f), ['/x_controller', '/y_controller']) is None
    assert params_file_miss(str(f), ['/m2/x_controller', '/m2/y_controller']) == (
        'nothing in it is for /m2/x_controller or /m2/y_controller '
        '(its entries: /y_controller, /**/z_observer)'
    )
    assert params_file_miss(str(f), ['/m2/z_observer']) is None


def test_parameter_rules() -> None:
    assert parameter_rule_problem('pd.omega_c:=12.0') is None
    assert parameter_rule_problem('x_controller:pd.omega_c:=12.0') is None
    assert parameter_rule_problem('foo') == 'not NAME:=VALUE'
    assert parameter_rule_problem(':=3') == 'not NAME:=VALUE'


def test_rcl_errors_lose_their_source_locations() -> None:
    # The texts rcl (Jazzy) raises at rclpy.init for these inputs.
    mixed = (
        "failed to initialize rcl: Couldn't parse params file: '--params-file /tmp/b.yaml'. "
        "Error: Sequence should be of same type. Value type 'double' do not belong at "
        'line_num 3, at /project/src/parse.c:391, at /project/src/rcl/arguments.c:415'
    )
    assert rcl_error_message(mixed) == (
        "--params-file /tmp/b.yaml: sequence should be of same type. Value type 'double' "
        'do not belong at line_num 3'
    )
    value_first = (
        "failed to initialize rcl: Couldn't parse params file: '--params-file /tmp/c.yaml'. "
        'Error: Cannot have a value before ros__parameters at line 1\n, at '
        '/project/src/parse.c:806, at /project/src/rcl/arguments.c:415'
    )
    assert rcl_error_message(value_first) == (
        '--params-file /tmp/c.yaml: cannot have a value before ros__parameters at line 1'
    )
