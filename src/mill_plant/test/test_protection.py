"""The drive's protection in lockstep (mill_plant.protection): whatever a sender commands, no
axis moves faster than the speed limit or out of the travel. ROS-free: the simulated machine
of the plant node's defaults (Beltrán 2013's x axis, 10 N·m at most) stepped as the lockstep
drive and the offline simulator step it."""

from __future__ import annotations

import math

import pytest
from mill_common.hold_window import HoldWindow
from mill_plant.command_delay import CommandDelay
from mill_plant.command_table import CommandTable
from mill_plant.config import parameter_specs
from mill_plant.motion_guard import MotionGuard
from mill_plant.protection import Protection
from mill_plant.simulated_machine import SimulatedMachine

DEFAULTS = {name: spec.default for name, spec in parameter_specs()}
DT_NS = 1_000_000  # the defaults' sample period, 1 ms
ROGUE = 10.0  # [N·m] the rogue sender: the axis's whole torque, every step


class Run:
    """Lockstep steps of axis x under one command per step, as the drive applies them."""

    def __init__(self, start: float, speed_limit: float, travel: tuple[float, float]) -> None:
        values = {
            **DEFAULTS,
            'axes': ['x'],
            'initial_position': [start, -0.105, -0.005],
            'cutting_model': 'none',  # the axis alone: its acceleration is the torque's
        }
        self.machine = SimulatedMachine(values)
        self.table = CommandTable(['x'], HoldWindow.from_node_values(values), DT_NS)
        guard = MotionGuard(['x'], speed_limit, values['hold_deviation'], {'x': travel})
        self.protection = Protection(self.table, guard)
        self.delay = CommandDelay(0, 1)
        self.x: list[float] = []  # true position after each step [m]
        self.v: list[float] = []  # true velocity after each step [m/s]
        self.stops: list[tuple[int, str]] = []
        self.rearmed: list[int] = []
        self.k = 0

    def step(self, command: float, guarded: bool = True) -> None:
        ns = self.k * DT_NS
        measured = self.machine.read()
        if guarded:
            self.table.offer('x', ns, command)
            step = self.protection.lockstep_step(ns, measured, self.delay)
            self.stops += [(self.k, why) for why in step.stopped.values()]
            self.rearmed += [self.k] * len(step.rearmed)
            self.machine.write(step.efforts)
        else:
            self.machine.write([command])
        self.machine.advance(DT_NS * 1e-9)
        self.x.append(self.machine.plant.position[0])
        self.v.append(self.machine.plant.velocity[0])
        self.k += 1


T = DT_NS * 1e-9


def acceleration(run: Run) -> float:
    """The rogue torque's acceleration of the axis [m/s²], from its first step (from rest:
    about 10 N·m · 2π/pitch over the mass and the screw's inertia, 210 m/s²)."""
    return run.v[0] / T


def test_unguarded_the_rogue_command_runs_the_axis_off_the_machine() -> None:
    # The attack of issue 37 without the guard: 300 steps of 10 N·m from x = -75 mm.
    run = Run(-0.075, 0.5, (-1.0, 1.0))
    for _ in range(300):
        run.step(ROGUE, guarded=False)
    assert 200.0 < acceleration(run) < 220.0
    assert run.x[-1] > 1.0  # past the travel
    assert max(run.v) > 10.0  # twenty times the speed limit


def test_a_rogue_torque_is_stopped_at_the_speed_limit_and_stays_stopped() -> None:
    run = Run(-0.075, 0.5, (-1.0, 1.0))
    for _ in range(300):
        run.step(ROGUE)
    (k, why), *more = run.stops
    assert more == [] and run.rearmed == []  # latched: valid commands alone never re-arm
    assert 'above the limit 500 mm/s' in why
    # The guard reads the mean speed over the last period: it sees the limit crossed at
    # most 1.5 periods after the crossing, and the brake holds the axis from that step on.
    a = acceleration(run)
    peak = max(abs(v) for v in run.v)
    assert 0.5 < peak <= 0.5 + 1.5 * a * T
    assert all(v == 0.0 for v in run.v[k:])
    # It moved peak²/2a (under a mm), then not a nanometre more.
    moved = run.x[-1] + 0.075
    assert moved == pytest.approx(peak**2 / (2 * a), rel=0.05)
    assert moved < 0.001
    assert run.x[k:] == [run.x[k]] * (300 - k)


def test_a_rogue_torque_never_leaves_the_travel() -> None:
    # No speed limit to speak of: the travel alone stops it, 20 mm ahead of the axis.
    hi = -0.055
    run = Run(-0.075, 100.0, (-1.0, hi))
    for _ in range(300):
        run.step(ROGUE)
    (k, why), *more = run.stops
    assert more == [] and f'travel.max {hi:g} m' in why
    assert max(run.x) <= hi
    # Stopped at the last step before the end: a step at the speed it had, and no earlier.
    v = run.v[k - 1]
    assert hi - run.x[-1] <= v * T + acceleration(run) * T**2
    assert all(v == 0.0 for v in run.v[k:])


def test_the_owner_re_arms_a_stopped_axis_with_a_brake_request_then_a_command() -> None:
    run = Run(-0.075, 0.5, (-1.0, 1.0))
    while not run.stops:
        run.step(ROGUE)
    stopped_at = run.x[-1]
    run.step(0.0)  # a valid command: still stopped
    assert run.rearmed == [] and run.x[-1] == stopped_at
    run.step(math.nan)  # the owner's brake request acknowledges the stop
    assert run.rearmed == []
    run.step(-1.0)  # its valid command then re-arms: the axis moves again
    assert run.rearmed == [run.k - 1]
    run.step(-1.0)
    assert run.x[-1] < stopped_at


def test_a_stop_brakes_at_once_whatever_the_command_delay() -> None:
    run = Run(-0.075, 0.5, (-1.0, 1.0))
    run.delay = CommandDelay(3, 1)
    for _ in range(300):
        run.step(ROGUE)
    (k, _), *_ = run.stops
    # The delay holds the commands back (zero input for 3 steps), never the brake.
    assert run.v[:3] == [0.0, 0.0, 0.0]
    a = run.v[3] / T  # from its first step with the torque
    assert max(abs(v) for v in run.v) <= 0.5 + 1.5 * a * T
    assert all(v == 0.0 for v in run.v[k:])
