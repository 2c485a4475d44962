"""Switching the control law of a running job (issue 3): the x controller goes from adrc to
gpi mid-move by a parameter set, without a bump; a switch to a law with another output
unit is refused with its reason while the old law keeps running. The observer is re-tuned
while running, and a switch to an observer estimating in other units is refused."""

from __future__ import annotations

import math
import subprocess
import sys

import pytest
from diagnostic_msgs.msg import DiagnosticArray
from mill_common.ros import DATA_QOS, from_stamp
from sensor_msgs.msg import JointState

from mill_common import topics
from test.conftest import ParameterClient, ros_node, wait_until

T_NS = 1_000_000  # sample period of the slotting scenario


@pytest.mark.system
def test_controller_switch_mid_job_is_bumpless(ros_env) -> None:
    runner = subprocess.Popen(
        [sys.executable, '-m', 'mill_bringup.runner', 'slotting', '--duration', '6', '--quiet'],
        env=ros_env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    commands: dict[int, float] = {}
    switches: list[dict[str, str]] = []

    def on_command(msg: JointState) -> None:
        commands[from_stamp(msg.header.stamp)] = msg.effort[0]

    def on_diagnostics(msg: DiagnosticArray) -> None:
        for status in msg.status:
            if status.name == 'mill_controllers: x switch':
                switches.append({kv.key: kv.value for kv in status.values})

    try:
        with ros_node('switch_tester') as (node, executor):
            node.create_subscription(JointState, topics.joint_command('x'), on_command, DATA_QOS)
            node.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, on_diagnostics, 100)
            params = ParameterClient(node, executor, 'x_controller')

            def spin_until(predicate, timeout: float) -> bool:
                def step() -> bool:
                    executor.spin_once(timeout_sec=0.01)
                    return predicate() or runner.poll() is not None

                return wait_until(step, timeout, step=0.0) and predicate()

            assert spin_until(lambda: max(commands, default=0) >= 1.0e9, 300), 'job never ran'
            refused = params.set('controller', 'cascade_pi')
            assert not refused.successful and 'V' in refused.reason, refused.reason
            assert params.set('controller', 'gpi').successful
            assert spin_until(lambda: bool(switches), 60), 'no switch reported'
            assert params.get('controller') == {'controller': 'gpi'}
            # The observer: a gain change hands over (the estimate continues), a switch to
            # an observer estimating in volts is refused.
            observer = ParameterClient(node, executor, 'x_observer')
            refused = observer.set('observer', 'imbdo')
            assert not refused.successful and 'V' in refused.reason, refused.reason
            assert observer.set('gpi.omega_o', 600.0).successful
            spin_until(lambda: runner.poll() is not None, 300)  # collect to the end
        _out, err = runner.communicate(timeout=300)
    finally:
        if runner.poll() is None:
            runner.kill()
            runner.communicate()
    assert runner.returncode == 0, err[-3000:]

    (switch,) = switches
    assert switch['controller'] == 'gpi'
    ns = round(float(switch['time']) * 1e9 / T_NS) * T_NS
    old, new = float(switch['old_output']), float(switch['new_output'])
    # The switch sample outputs the old law's value: the command moves exactly as the old
    # law would have moved it, not by the new law's jump.
    assert commands[ns] == old
    assert math.isfinite(new) and new != old  # the new law alone would have sent another value
    # The new law answered every sample of the rest of the job (the plant waits for each).
    last = max(commands)
    missing = [k for k in range(ns, last + T_NS, T_NS) if k not in commands]
    assert last >= ns + 100 * T_NS and not missing, missing[:5]


@pytest.mark.system
def test_switch_to_a_law_that_joins_the_observer_model_mid_job(ros_env) -> None:
    """hatwesh, machine_pi → adaptive_pi designing with the rls observer's estimate: from
    the switch on the controller also waits for /mill/x/observer_state of each sample."""
    period_ns = 250_000
    runner = subprocess.Popen(
        [
            sys.executable,
            '-m',
            'mill_bringup.runner',
            'hatwesh',
            '--variant',
            'machine_pi',
            '--duration',
            '1.0',
            '--quiet',
        ],
        env=ros_env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    commands: dict[int, float] = {}
    switches: list[dict[str, str]] = []
    law_state: dict[str, float] = {}

    def on_command(msg: JointState) -> None:
        commands[from_stamp(msg.header.stamp)] = msg.effort[0]

    def on_law_state(msg: JointState) -> None:
        law_state.update(zip(msg.name, msg.position, strict=True))

    def on_diagnostics(msg: DiagnosticArray) -> None:
        for status in msg.status:
            if status.name == 'mill_controllers: x switch':
                switches.append({kv.key: kv.value for kv in status.values})

    try:
        with ros_node('switch_tester') as (node, executor):
            node.create_subscription(JointState, topics.joint_command('x'), on_command, DATA_QOS)
            node.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, on_diagnostics, 100)
            node.create_subscription(
                JointState, topics.controller_state('x'), on_law_state, DATA_QOS
            )
            params = ParameterClient(node, executor, 'x_controller')

            def spin_until(predicate, timeout: float) -> bool:
                def step() -> bool:
                    executor.spin_once(timeout_sec=0.01)
                    return predicate() or runner.poll() is not None

                return wait_until(step, timeout, step=0.0) and predicate()

            assert spin_until(lambda: max(commands, default=0) >= 0.2e9, 300), 'job never ran'
            assert params.set('adaptive_pi.model_source', 'observer').successful
            assert params.set('controller', 'adaptive_pi').successful
            # (the first change rebuilds machine_pi: two switches, or one if both changes
            # came before the same sample)
            assert spin_until(
                lambda: bool(switches) and switches[-1]['controller'] == 'adaptive_pi', 60
            ), 'no switch reported'
            spin_until(lambda: runner.poll() is not None, 300)  # collect to the end
        _out, err = runner.communicate(timeout=300)
    finally:
        if runner.poll() is None:
            runner.kill()
            runner.communicate()
    assert runner.returncode == 0, err[-3000:]
    assert switches[-1]['controller'] == 'adaptive_pi'
    ns = round(float(switches[-1]['time']) * 1e9 / period_ns) * period_ns
    assert commands[ns] == float(switches[-1]['old_output'])
    last = max(commands)
    missing = [k for k in range(ns, last + period_ns, period_ns) if k not in commands]
    assert last >= ns + 400 * period_ns and not missing, missing[:5]
    # The law designed its gains from the observer's estimate (its own RLS never ran).
    assert law_state['adapted'] == 1.0 and law_state['updates'] > 2000
