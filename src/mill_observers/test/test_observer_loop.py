"""The observer's sample step (ObserverLoop): the calls it makes on the observer core."""

from __future__ import annotations

import pytest
from mill_common.signals import Estimate
from mill_observers.base import Observer
from mill_observers.observer_loop import ObserverLoop


class Calls(Observer):
    PREFIX = 'calls'

    def __init__(self) -> None:
        self.calls: list[tuple[str, float]] = []

    @classmethod
    def from_parameters(cls, input_gain, sample_period, values):  # type: ignore[no-untyped-def]
        return cls()

    def correct(self, y: float) -> Estimate:
        self.calls.append(('correct', y))
        return Estimate(y, 0.0, 0.0)

    def predict(self, u: float) -> None:
        self.calls.append(('predict', u))


def test_the_first_sample_only_corrects_the_next_predict_with_the_command_before() -> None:
    core = Calls()
    loop = ObserverLoop(core, 0, 1e-3, 0.0)
    loop.step(1.0, 5.0)  # a command before the first state is not the loop's
    loop.step(2.0, 0.5)
    assert core.calls == [('correct', 1.0), ('predict', 0.5), ('correct', 2.0)]


def test_lost_periods_run_through_with_the_command_that_acted() -> None:
    core = Calls()
    loop = ObserverLoop(core, 1, 1e-3, 0.0)
    loop.step(0.0, None)
    core.calls.clear()
    loop.step(1.0, 0.25, missed=2)
    predicts = [u for name, u in core.calls if name == 'predict']
    assert len(predicts) == 3  # two lost periods and the one before this state


def test_a_replacement_starts_anew_and_continues_the_estimate() -> None:
    loop = ObserverLoop(Calls(), 0, 1e-3, 0.05)
    loop.step(1.0, None)
    new_core = Calls()
    loop = loop.replace(ObserverLoop(new_core, 0, 1e-3, 0.05))
    loop.step(2.0, 0.3)  # the new observer's first sample: no command before it
    assert new_core.calls == [('correct', 2.0)]


def test_a_braked_axis_keeps_its_disturbance_estimate() -> None:
    from mill_observers.eso import EsoParams, ExtendedStateObserver

    B, T = 20.0, 1e-3
    loop = ObserverLoop(
        ExtendedStateObserver(B, T, EsoParams(omega_o=200.0)), 1, T, 0.0, hold_torque=0.05
    )
    est = loop.step(0.0, None)
    assert est.disturbance == -B * 0.05  # the weight the hold torque balances
    for _ in range(500):  # the axis held by its brake: the commands are brake requests
        est = loop.step(0.0, float('nan'))
    assert abs(est.disturbance + B * 0.05) < 1e-9 * B


def test_a_released_axis_restarts_from_its_hold_torque_not_from_what_it_learnt_moving() -> None:
    from mill_observers.eso import EsoParams, ExtendedStateObserver

    B, T = 20.0, 1e-3
    loop = ObserverLoop(
        ExtendedStateObserver(B, T, EsoParams(omega_o=200.0)), 1, T, 0.0, hold_torque=0.05
    )
    loop.step(0.0, None)
    x = v = 0.0
    for _ in range(2000):  # moving against 3 m/s² of friction and load, at 0.2 N·m
        est = loop.step(x, 0.2)
        a = B * 0.2 - 3.0
        x, v = x + v * T + 0.5 * a * T * T, v + a * T
    assert est.disturbance == pytest.approx(-3.0, abs=0.05)
    for _ in range(50):  # stopped and braked
        loop.step(x, float('nan'))
    est = loop.step(x, 0.1)  # released: at rest, the weight the hold torque balances
    assert est.velocity == 0.0 and est.disturbance == pytest.approx(-B * 0.05)


def test_tick_jitter_is_run_through_when_the_stamps_tell_it() -> None:
    # A double integrator under a constant command, sampled by a drive whose ticks come
    # up to 30 % of a period early or late: told the real intervals, the observer follows
    # the motion; taking every interval for one period, its velocity is off.
    import math

    from mill_observers.eso import EsoParams, ExtendedStateObserver

    B, T = 20.0, 1e-3
    told, untold = (
        ObserverLoop(ExtendedStateObserver(B, T, EsoParams(omega_o=300.0)), 1, T, 0.0) for _ in '12'
    )
    x = v = 0.0
    u = 0.01
    errors = {'told': 0.0, 'untold': 0.0}
    acted, late = None, 0.0
    for k in range(2000):
        for name, loop in (('told', told), ('untold', untold)):
            # `late`: how much the interval since the last state was off one period
            est = loop.step(x, acted, 0, late if name == 'told' else 0.0)
            if k > 1000:
                errors[name] = max(errors[name], abs(est.velocity - v))
        acted = u
        late = 0.3 * math.sin(1.7 * k)  # the drive's next tick, early or late
        h = T * (1.0 + late)
        a = B * u
        x, v = x + v * h + 0.5 * a * h * h, v + a * h
    assert errors['told'] < 0.2 * errors['untold']
