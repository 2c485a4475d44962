"""The spindle gate and the spindle speeds read off the reference (mill_plant.spindle)."""

from __future__ import annotations

from types import SimpleNamespace

from mill_plant.cutting import StepForce, StepParams
from mill_plant.spindle import SpindleGate, SpindleTrack, spindle_values


def test_the_gate_passes_the_force_only_while_the_spindle_runs() -> None:
    gate = SpindleGate(StepForce(StepParams(force=[1.0, 2.0, 3.0], start_time=0.0)), running=False)
    assert gate.force(1.0, (0, 0, 0), (0, 0, 0)) == (0.0, 0.0, 0.0)
    gate.running = True
    assert gate.force(1.0, (0, 0, 0), (0, 0, 0)) == (1.0, 2.0, 3.0)


def test_the_track_holds_the_newest_speed_and_knows_what_was_said() -> None:
    track = SpindleTrack()
    assert not track.known(0) and track.at(0) == 0.0  # off before the reference says
    track.offer([0, 10, 20], [0.0, 1800.0, 1800.0])
    assert track.known(20) and not track.known(21)
    assert [track.at(ns) for ns in (0, 9, 10, 25)] == [0.0, 0.0, 1800.0, 1800.0]
    track.offer([20, 30], [0.0, 0.0])  # a later message replaces what it covers
    assert track.at(20) == 0.0 and track.known(30)
    track.forget_before(25)
    assert track.at(25) == 0.0 and track.at(30) == 0.0 and track.known(30)


def test_spindle_values_of_a_reference_message() -> None:
    def point(*positions: float) -> SimpleNamespace:
        return SimpleNamespace(positions=positions)

    names = ['x', 'y', 'z', 'spindle']
    assert spindle_values(names, [point(0, 0, 0, 1800), point(0, 0, 0, 0)]) == [1800.0, 0.0]
    assert spindle_values(['x', 'y', 'z'], [point(0, 0, 0)]) is None  # no spindle programmed
    assert spindle_values(names, [point(0, 0, 0)]) is None  # a short point
    assert spindle_values(names, [point(0, 0, 0, float('nan'))]) is None
