"""The observer node's bookkeeping (mill_observers.observer_steps): which state is stepped
when, with which command, and the contest rule: a contested command is the step's brake, a
contested state's step is passed. ROS-free."""

from __future__ import annotations

import math

from mill_common.timing import Lockstep, Realtime
from mill_observers.observer_steps import AGAIN, MAX_COAST, PASS, PAST, STEP, WAIT, ObserverSteps

T = 1_000_000  # the sample period [ns]


def _kinds(steps: ObserverSteps, started: bool = True) -> list[tuple[str, int, float | None]]:
    return [(s.kind, s.ns, s.acted) for s in steps.due(lambda: started)]


def test_lockstep_a_state_waits_for_the_command_answering_the_one_before() -> None:
    steps = ObserverSteps(Lockstep(T))
    steps.state(0, 1e-3, contested=False)
    assert _kinds(steps, started=False) == [(STEP, 0, None)]  # the first: no command yet
    steps.state(T, 2e-3, contested=False)
    assert _kinds(steps) == [(WAIT, T, None)]
    assert steps.last_ns == 0 and T in steps.states  # not stepped
    assert steps.commanded(0, 0.5)
    (step,) = steps.due(lambda: True)
    assert (step.kind, step.ns, step.y, step.acted) == (STEP, T, 2e-3, 0.5)
    assert steps.commands == {} and steps.last_ns == T


def test_a_contested_command_brakes_the_steps_valid_command_not_used_yet() -> None:
    steps = ObserverSteps(Lockstep(T))
    steps.state(0, 0.0, contested=False)
    list(steps.due(lambda: False))
    assert steps.commanded(0, 0.5)  # the real controller's, first
    assert steps.brakes_pending(0)  # the copy's: the drive takes the step as a brake
    assert math.isnan(steps.commands[0])
    steps.state(T, 0.0, contested=False)
    (step,) = steps.due(lambda: True)
    assert step.kind == STEP and step.acted is not None and math.isnan(step.acted)


def test_a_contested_command_first_is_taken_as_a_brake_request_by_the_node() -> None:
    steps = ObserverSteps(Lockstep(T))
    assert not steps.brakes_pending(0)  # nothing to brake yet: the node takes it as NaN
    assert steps.commands == {}
    assert steps.commanded(0, math.nan)
    assert math.isnan(steps.commands[0]) and math.isnan(steps.newest_command or 0.0)


def test_a_contested_state_is_passed_and_the_next_waits_for_its_brake() -> None:
    steps = ObserverSteps(Lockstep(T))
    steps.state(0, 0.0, contested=False)
    list(steps.due(lambda: False))
    steps.commanded(0, 0.5)
    steps.state(T, 9.0, contested=True)  # from one of two plants
    assert _kinds(steps) == [(PASS, T, None)]
    assert steps.last_ns == T and steps.states == {} and steps.contested_states == set()
    assert steps.commands == {}  # the command of 0 acted before a state not taken
    steps.state(2 * T, 0.0, contested=False)
    assert _kinds(steps) == [(WAIT, 2 * T, None)]  # the controller's answer to T: a brake
    steps.commanded(T, math.nan)
    (step,) = steps.due(lambda: True)
    assert step.ns == 2 * T and step.acted is not None and math.isnan(step.acted)


def test_states_not_after_the_last_one_stepped() -> None:
    lockstep = ObserverSteps(Lockstep(T))
    assert lockstep.behind(0) is None  # nothing stepped yet
    lockstep.state(T, 0.0, contested=False)
    list(lockstep.due(lambda: False))
    assert (lockstep.behind(T), lockstep.behind(0), lockstep.behind(2 * T)) == (AGAIN, PAST, None)
    assert not lockstep.commanded(0, 0.1)  # answers a state before the last: kept for none
    assert lockstep.commands == {} and lockstep.newest_command == 0.1
    realtime = ObserverSteps(Realtime(T))
    realtime.state(T, 0.0, contested=False)
    list(realtime.due(lambda: False))
    assert (realtime.behind(T), realtime.behind(0)) == (PAST, PAST)  # nothing is offered again


def test_realtime_steps_the_newest_state_with_the_newest_command_and_the_periods_missed() -> None:
    steps = ObserverSteps(Realtime(T))
    steps.state(0, 0.0, contested=False)
    assert _kinds(steps) == [(STEP, 0, None)]
    steps.state(T, 1.0, contested=False)
    (held,) = steps.due(lambda: True)
    assert held.acted is not None and math.isnan(held.acted)  # braked before its first command
    assert not steps.commanded(T, 0.25)  # no state waits for it
    steps.state(2 * T, 2.0, contested=False)
    steps.state(4 * T + T // 4, 3.0, contested=False)  # the newest: the older one is dropped
    (step,) = steps.due(lambda: True)
    assert (step.ns, step.y, step.acted, step.missed) == (4 * T + T // 4, 3.0, 0.25, 2)
    assert math.isclose(step.late, 0.25) and steps.states == {}
    steps.state(step.ns + 1000 * T, 4.0, contested=False)
    (coast,) = steps.due(lambda: True)
    assert coast.missed == MAX_COAST  # long silence: the model coasts no further


def test_a_rebuilt_observer_forgets_the_commands_kept() -> None:
    steps = ObserverSteps(Lockstep(T))
    steps.commanded(0, 0.5)
    steps.forget_commands()
    assert steps.commands == {} and steps.newest_command == 0.5
