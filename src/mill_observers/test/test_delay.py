"""An observer in a loop with one sample of delay: it predicts with the command that acts."""

from __future__ import annotations

import math

import pytest
from mill_common.signals import AxisReference, ControlInputs
from mill_controllers.pd_law import AdrcController, PdGains
from mill_observers.delay import DelayCompensation
from mill_observers.gpi import GpiObserver, GpiParams
from mill_observers.imbdo import Imbdo

B = 20.964  # Beltrán 2013 Table 1, x axis [m/s² per N·m]
T = 1e-3


def run(delay: int, compensate: bool, steps: int = 3000) -> list[float]:
    """A double integrator x'' = b u + 1 m/s² under ADRC, the command applied `delay` late."""
    observer = GpiObserver(B, T, GpiParams(omega_o=700.0, zeta_o=0.7071, pole_o=700.0))
    comp = DelayCompensation(observer, delay if compensate else 0, T)
    law = AdrcController(B, T, PdGains(torque_limit=math.inf))
    x = v = 0.0
    queue = [0.0] * delay
    out = []
    lead = delay if compensate else 0
    for k in range(steps):
        est = comp.correct(x)
        y = est.position if lead else x
        u = law.compute(ControlInputs((k + lead) * T, y, AxisReference(0.001, 0.0, 0.0), est))
        queue.append(u)
        a = B * queue.pop(0) + 1.0
        x, v = x + v * T + 0.5 * a * T * T, v + a * T
        comp.command(u)
        out.append(x)
    return out


def test_without_delay_it_is_the_plain_observer() -> None:
    plain = GpiObserver(B, T)
    wrapped = DelayCompensation(GpiObserver(B, T), 0, T)
    for k in range(50):
        y = 1e-3 * math.sin(0.1 * k)
        assert wrapped.correct(y) == plain.correct(y)
        wrapped.command(0.01 * k)
        plain.predict(0.01 * k)


def test_one_sample_of_delay_is_stable_only_when_compensated() -> None:
    # Uncompensated, the observer predicts with u(k) while u(k-1) acts: the disturbance
    # estimate absorbs the difference and the 700 rad/s compensation loop grows.
    wild = run(1, compensate=False, steps=600)
    assert not all(math.isfinite(x) and abs(x) < 1.0 for x in wild)
    tame = run(1, compensate=True)
    # Settles at the 1 mm set point as the undelayed loop does (to the float rounding of
    # the exact ZOH model, which both share).
    assert tame[-1] == pytest.approx(run(0, compensate=True)[-1], abs=1e-12)
    assert max(abs(x - 0.001) for x in tame[-500:]) < 1e-12


def test_the_estimate_is_the_state_n_samples_ahead() -> None:
    # x'' = b u on a double integrator, u constant: the GPI model propagation is exact, so
    # after convergence the estimate of sample k+2 equals the true position at k+2.
    u, n = 0.01, 2
    comp = DelayCompensation(GpiObserver(B, T), n, T)
    x = v = 0.0
    history = []
    for _ in range(400):
        est = comp.correct(x)
        comp.command(u)
        a = B * u
        history.append((x, est.position))
        x, v = x + v * T + 0.5 * a * T * T, v + a * T
    # With u constant the commands acting are all u (after the first n samples).
    for k in range(300, 397):
        assert history[k][1] == pytest.approx(history[k + n][0], rel=1e-9)


def test_observers_without_a_model_extrapolate_the_position() -> None:
    comp = DelayCompensation(Imbdo(0.0, 1e-4), 1, 1e-4)
    comp.correct(0.0)
    comp.command(0.0)
    est = comp.correct(1e-6)
    assert est.position == pytest.approx(1e-6 + 1e-4 * est.velocity)


def test_non_finite_commands_count_as_no_input_and_bad_delays_are_refused() -> None:
    comp = DelayCompensation(GpiObserver(B, T), 1, T)
    comp.correct(0.0)
    comp.command(math.nan)
    assert list(comp.pending) == [0.0]
    with pytest.raises(ValueError, match='delay'):
        DelayCompensation(GpiObserver(B, T), -1, T)


def test_a_lost_period_runs_on_with_the_command_that_acted_over_it() -> None:
    # One sample of delay, constant motion: after the state of k, u(k) was sent and acts
    # over [k+1, k+2); the state of k+1 is lost. The observer must run that period with
    # u(k) (the held command), not with u(k-1), which acted the period before.
    def observer_after(coast_with: float | None) -> GpiObserver:
        comp = DelayCompensation(GpiObserver(B, T), 1, T)
        x = v = 0.0
        us = [0.0] * 300 + [0.2]  # u(k-1) = 0, then u(k) = 0.2 N·m, held
        applied = 0.0
        for u in us:
            comp.correct(x)
            comp.command(u)
            a = B * applied
            x, v = x + v * T + 0.5 * a * T * T, v + a * T
            applied = u  # one sample of delay
        if coast_with is not None:
            comp.coast(coast_with)
        return comp.observer

    lost = observer_after(0.2)
    # The truth: the same run with the lost period's state measured (predict with u(k)).
    ref = DelayCompensation(GpiObserver(B, T), 1, T)
    x = v = 0.0
    applied = 0.0
    for u in [0.0] * 300 + [0.2]:
        ref.correct(x)
        ref.command(u)
        a = B * applied
        x, v = x + v * T + 0.5 * a * T * T, v + a * T
        applied = u
    ref.observer.predict(0.2)  # the period [k+1, k+2) with the command that acted
    assert lost.state[1] == pytest.approx(ref.observer.state[1], rel=1e-12)
