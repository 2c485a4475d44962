"""Issue 37, point 6: what ended a node with a traceback, or was taken silently, ends its
start-up with one line and exit code 2: a value rclpy itself refuses (`use_sim_time:=maybe`),
a gain no law or observer can be built with (running or not), a count too large to run
(`substeps:=1e9`), and a parameter file with YAML aliases (the alias bomb)."""

from __future__ import annotations

from pathlib import Path

import pytest

from test.conftest import NodeProcess

PLANT = ('mill_plant.plant_node', 'plant_node', 'plant')
CONTROLLER = ('mill_controllers.axis_controller_node', 'axis_controller_node', 'x_controller')
OBSERVER = ('mill_observers.observer_node', 'observer_node', 'x_observer')
OVERFLOW = "OverflowError: (34, 'Numerical result out of range')"

# (node, ros arguments, the one line after `EXECUTABLE: error: `)
CASES = [
    (
        CONTROLLER,
        ('-p', 'use_sim_time:=maybe'),
        "Trying to set parameter 'use_sim_time' to 'maybe' of type 'STRING', expecting type "
        "'BOOL': use_sim_time",
    ),
    (
        CONTROLLER,
        ('-p', 'gpi.omega_n:=1e300'),
        f'gpi.omega_n=1e+300: gpi (not the running law): {OVERFLOW}',
    ),
    (
        CONTROLLER,
        ('-p', 'controller:=sliding_gpi', '-p', 'sliding_gpi.omega_n:=1e300'),
        f"controller='sliding_gpi', sliding_gpi.omega_n=1e+300: {OVERFLOW}",
    ),
    (
        OBSERVER,
        ('-p', 'dfo.omega_o:=1e300'),
        f'dfo.omega_o=1e+300: dfo (not the running observer): {OVERFLOW}',
    ),
    (
        PLANT,
        ('-p', 'substeps:=1000000000'),
        'invalid parameter substeps=1000000000: must be a whole number in [1, 1000]',
    ),
]

BOMB = 'a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]\n' + ''.join(
    f'{n}: &{n} [{", ".join([f"*{p}"] * 9)}]\n' for p, n in zip('abcdefgh', 'bcdefghi', strict=True)
)


def _one_line(proc: NodeProcess) -> str:
    code, _out, err = proc.wait(timeout=60)
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2, err[-2000:]
    assert len(lines) == 1 and 'Traceback' not in err, err[-2000:]
    return lines[0]


@pytest.mark.system
@pytest.mark.parametrize(
    ('node', 'args', 'line'), CASES, ids=[f'{n[1]}-{a[-1]}' for n, a, _ in CASES]
)
def test_a_start_up_refusal_is_one_line_and_exit_2(start_node, node, args, line) -> None:
    module, executable, name = node
    got = _one_line(start_node(module, name, *args, params_file=False))
    assert got == f'{executable}: error: {line}'


@pytest.mark.system
def test_a_parameter_file_with_aliases_is_refused_in_one_line(start_node, tmp_path: Path) -> None:
    path = tmp_path / 'bomb.yaml'
    path.write_text('x_controller:\n  ros__parameters:\n    controller: pd\n' + BOMB)
    module, executable, name = CONTROLLER
    got = _one_line(start_node(module, name, '--params-file', str(path), params_file=False))
    assert got == (
        f'{executable}: error: --params-file {path}: an anchor (&a) at line 4, column 4: '
        'anchors are refused'
    )
