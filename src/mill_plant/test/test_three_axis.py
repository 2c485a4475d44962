"""Three-axis rigid plant: RK4 accuracy, stick-slip, faults, disturbance, determinism."""

from __future__ import annotations

import itertools
import math
import random

import numpy as np
import pytest
from mill_models.axis_data import BELTRAN_TABLE1
from mill_plant.axis_plant import StepReport
from mill_plant.cutting import NoCutting, StepForce
from mill_plant.kline_force import KlineCuttingForce
from mill_plant.three_axis import ThreeAxisPlant
from scipy.integrate import solve_ivp

AXES = [BELTRAN_TABLE1[a] for a in 'xyz']
DT = 1e-3


def _set_velocity(plant: ThreeAxisPlant, velocity: tuple[float, float, float]) -> None:
    """Start the axes moving: the plant has no public state setter, and tests need one."""
    plant._v = list(velocity)


def _reference(kline: KlineCuttingForce, x0, v0, torque, t_end: float) -> np.ndarray:
    """Same equations by scipy DOP853; valid only while no velocity reaches zero.

    The chip is the tool's x-y path since the previous tooth, p(t) - p(t - T_z): a delay
    equation, solved by steps of one tooth period, each using the dense output of the one
    before for p(t - T_z) (the tool stood at x0 before t = 0, as the plant tells the model).
    """
    drive = [torque[i] / AXES[i].lead for i in range(3)]
    m_e = [a.effective_mass for a in AXES]
    c_e = [a.effective_damping for a in AXES]
    mu = [a.coulomb_friction for a in AXES]
    signs = [math.copysign(1.0, v) for v in v0]
    tz = kline.tooth_period
    previous = None  # dense output of the step before

    def past(t: float) -> tuple[float, float]:
        if previous is None or t <= 0.0:
            return x0[0], x0[1]
        y = previous(t)
        return float(y[0]), float(y[1])

    def rhs(t: float, y: np.ndarray) -> list[float]:
        px, py = past(t - tz)
        depth = kline.workpiece_top - y[2]
        f = kline.chip_force(t, (y[0], y[1], y[2]), (y[0] - px, y[1] - py), depth)
        acc = [(drive[i] - f[i] - c_e[i] * y[3 + i] - mu[i] * signs[i]) / m_e[i] for i in range(3)]
        return [y[3], y[4], y[5], *acc]

    state, t0 = [*x0, *v0], 0.0
    while t0 < t_end:
        t1 = min(t0 + tz, t_end)
        sol = solve_ivp(
            rhs,
            (t0, t1),
            state,
            method='DOP853',
            rtol=1e-12,
            atol=1e-15,
            max_step=1e-3,
            dense_output=True,
        )
        assert sol.success
        previous, state, t0 = sol.sol, sol.y[:, -1], t1
    return np.asarray(state)


@pytest.mark.parametrize(
    ('specific_energy', 'helix_deg', 'torque'),
    [
        # No axial force: a shallow realistic cut in x-y, z plunging slowly in air-like balance.
        (1.37e9, 0.0, (0.0152, 0.00826, -1.566e-4)),
        # With the axial force (kinks at tooth entry); a weak material keeps every velocity
        # away from zero while z is pulled down into the work.
        (1.0e7, 45.0, (0.0152, 0.00826, -1.566e-4)),
    ],
)
def test_rk4_matches_dop853_with_kline_force(specific_energy, helix_deg, torque) -> None:
    kline = KlineCuttingForce(
        specific_energy=specific_energy, helix_angle=math.radians(helix_deg), workpiece_top=-0.0048
    )
    x0 = (-0.06, -0.08, -0.005)
    v0 = (0.01, 0.01, -0.0002)
    plant = ThreeAxisPlant(AXES, kline, initial_position=x0, substeps=4)
    _set_velocity(plant, v0)
    kline.commit(0.0, x0, v0)  # the state the test set replaces the one the plant committed
    lowest = [abs(v) for v in v0]
    cutting_steps = 0
    for _ in range(1000):
        plant.step(torque, DT)
        lowest = [
            min(lo, v * math.copysign(1.0, v0_i))
            for lo, v, v0_i in zip(lowest, plant.velocity, v0, strict=True)
        ]
        cutting_steps += plant.cutting_force()[1] != 0.0
    assert plant.time == pytest.approx(1.0, abs=1e-12)
    assert min(lowest) > 0.0, 'the comparison needs velocities that never reach zero'
    assert cutting_steps > 900, 'the tool must be cutting for the comparison to mean anything'
    ref = _reference(kline, x0, v0, torque, 1.0)
    for i in range(3):
        assert abs(plant.position[i] - ref[i]) < 1e-9
        assert abs(plant.velocity[i] - ref[3 + i]) < 1e-8


def test_stiction_below_breakaway_keeps_axes_exactly_at_rest() -> None:
    x0 = (0.01, -0.02, 0.003)
    plant = ThreeAxisPlant(AXES, NoCutting(), initial_position=x0)
    torque = tuple(
        0.95 * a.coulomb_friction * a.lead * s for a, s in zip(AXES, (1, -1, 1), strict=True)
    )
    for _ in range(1000):
        plant.step(torque, DT)
        assert plant.velocity == (0.0, 0.0, 0.0)
        assert plant.position == x0


def test_stiction_holds_against_a_sub_breakaway_cutting_force() -> None:
    plant = ThreeAxisPlant(AXES, StepForce((0.2, -0.25, 0.29), start_time=0.0))
    for _ in range(100):
        plant.step((0.0, 0.0, 0.0), DT)
    assert plant.velocity == (0.0, 0.0, 0.0)
    assert plant.position == (0.0, 0.0, 0.0)
    # ...and a force above mu moves the axis against it (here -x).
    moved = ThreeAxisPlant(AXES, StepForce((0.31, 0.0, 0.0), start_time=0.0))
    for _ in range(100):
        moved.step((0.0, 0.0, 0.0), DT)
    assert moved.velocity[0] < 0.0 and moved.position[0] < 0.0


def test_just_above_breakaway_moves() -> None:
    plant = ThreeAxisPlant(AXES, NoCutting())
    torque = tuple(1.01 * a.coulomb_friction * a.lead for a in AXES)
    for _ in range(1000):
        plant.step(torque, DT)
    for i, axis in enumerate(AXES):
        # m_e v' = 0.01 mu - c_e v from rest: v = (0.01 mu / c_e)(1 - exp(-c_e t / m_e))
        net = 0.01 * axis.coulomb_friction
        rate = axis.effective_damping / axis.effective_mass
        expected_v = net / axis.effective_damping * (1.0 - math.exp(-rate * 1.0))
        assert plant.velocity[i] == pytest.approx(expected_v, rel=1e-9)
        assert plant.position[i] > 0.0


def _sign_changes(values: list[float]) -> int:
    signs = [v > 0.0 for v in values if v != 0.0]
    return sum(a != b for a, b in itertools.pairwise(signs))


def test_slow_sinusoidal_torque_gives_no_velocity_chatter() -> None:
    # Peak drive 1.5 mu: each axis breaks away, then friction stops it while |tau/a| < mu
    # again, so it must stay stuck until the torque exceeds breakaway the other way.
    plant = ThreeAxisPlant(AXES, NoCutting())
    amplitude = [1.5 * a.coulomb_friction * a.lead for a in AXES]
    torques: list[float] = []
    velocities: list[list[float]] = [[], [], []]
    rest_after_first_motion = 0
    for k in range(4000):
        phase = math.sin(2.0 * math.pi * 0.5 * (k + 0.5) * DT)
        torques.append(phase)
        plant.step(tuple(amp * phase for amp in amplitude), DT)
        for i in range(3):
            velocities[i].append(plant.velocity[i])
        rest_after_first_motion += k > 500 and plant.velocity[0] == 0.0
    torque_changes = _sign_changes(torques)
    assert torque_changes == 3
    for i in range(3):
        changes = _sign_changes(velocities[i])
        assert 1 <= changes <= torque_changes
    # The axis really sticks around each torque reversal, exactly at rest.
    assert rest_after_first_motion > 300


def test_non_finite_torque_brakes_only_that_axis() -> None:
    start = (0.01, 0.02, -0.003)
    faulty = ThreeAxisPlant(AXES, StepForce((0.5, -0.7, 1.0), start_time=0.002), start)
    clean = ThreeAxisPlant(AXES, StepForce((0.5, -0.7, 1.0), start_time=0.002), start)
    torque = (0.01, -0.02, 0.03)
    for _ in range(20):
        faulty.step(torque, DT)
        clean.step(torque, DT)
    assert faulty.velocity[1] != 0.0
    held = faulty.position[1]
    for bad in (math.nan, math.inf, -math.inf):
        report = faulty.step((torque[0], bad, torque[2]), DT)
        clean.step(torque, DT)
        assert report.faulted == (False, True, False)
        assert report.saturated == (False, False, False)
        assert faulty.velocity[1] == 0.0
        assert faulty.position[1] == held
        assert all(math.isfinite(v) for v in (*faulty.position, *faulty.velocity))
        # uncoupled axes (no position/velocity-dependent force): bit-identical to the clean run
        for i in (0, 2):
            assert faulty.position[i] == clean.position[i]
            assert faulty.velocity[i] == clean.velocity[i]
    report = faulty.step(torque, DT)
    assert report.faulted == (False, False, False)
    assert faulty.velocity[1] != 0.0  # recovers once the torque is finite again


def test_torque_is_clipped_and_reported() -> None:
    limited = ThreeAxisPlant(AXES, NoCutting(), max_torque=(0.1, 0.2, math.inf))
    reference = ThreeAxisPlant(AXES, NoCutting())
    report = limited.step((0.5, -0.15, 7.0), DT)
    reference.step((0.1, -0.15, 7.0), DT)
    assert report == StepReport((True, False, False), (False, False, False), (0.1, -0.15, 7.0))
    assert limited.position == reference.position
    assert limited.velocity == reference.velocity
    assert limited.step((-1.0, 0.0, 0.0), DT).applied_torque == (-0.1, 0.0, 0.0)


def test_disturbance_of_sliding_axes_without_cutting() -> None:
    plant = ThreeAxisPlant(AXES, NoCutting())
    drive = (0.02, -0.03, 0.01)
    for _ in range(50):
        plant.step(drive, DT)
    torque = (0.001, -0.002, 0.0005)
    xi = plant.disturbance(torque)
    for i, axis in enumerate(AXES):
        v = plant.velocity[i]
        sign = math.copysign(1.0, v)
        resisting = axis.effective_damping * v + axis.coulomb_friction * sign
        expected = -resisting / axis.effective_mass
        assert xi[i] == pytest.approx(expected, rel=1e-14)
    # Consistency with the motion: over a short step, dv/dt = b tau + xi.
    before = plant.velocity
    plant.step(torque, 1e-6)
    for i, axis in enumerate(AXES):
        accel = (plant.velocity[i] - before[i]) / 1e-6
        assert accel == pytest.approx(axis.input_gain * torque[i] + xi[i], rel=1e-6)


def test_disturbance_includes_the_cutting_force() -> None:
    force = (40.0, -25.0, 10.0)
    plant = ThreeAxisPlant(AXES, StepForce(force, start_time=0.01))
    drive = (0.05, -0.05, 0.05)
    for _ in range(20):
        plant.step(drive, DT)
    assert plant.time > 0.01
    assert plant.cutting_force() == force
    xi = plant.disturbance(drive)
    for i, axis in enumerate(AXES):
        v = plant.velocity[i]
        assert v != 0.0
        friction = axis.coulomb_friction * math.copysign(1.0, v)
        expected = -(axis.effective_damping * v + friction + force[i]) / axis.effective_mass
        assert xi[i] == pytest.approx(expected, rel=1e-14)


def test_disturbance_at_rest() -> None:
    plant = ThreeAxisPlant(AXES, NoCutting())
    small = tuple(0.5 * a.coulomb_friction * a.lead for a in AXES)
    xi = plant.disturbance(small)
    for i, axis in enumerate(AXES):  # stuck: x'' = 0, so xi = -b tau
        assert xi[i] == pytest.approx(-axis.input_gain * small[i], rel=1e-14)
    large = (0.01, -0.01, 0.01)
    xi = plant.disturbance(large)
    for i, axis in enumerate(AXES):  # breaking away: only friction opposes, v = 0
        sign = math.copysign(1.0, large[i])
        assert xi[i] == pytest.approx(-axis.coulomb_friction * sign / axis.effective_mass)
    faulted = plant.disturbance((math.nan, 0.0, 0.0))
    assert math.isnan(faulted[0]) and faulted[1] == 0.0


def _run(seed: int) -> list[tuple[float, ...]]:
    plant = ThreeAxisPlant(
        AXES,
        KlineCuttingForce(),
        initial_position=(-0.075, -0.105, -0.005),
        max_torque=(0.5, 0.5, 0.5),
    )
    rng = random.Random(seed)
    history = []
    for k in range(2000):
        # Mostly moderate torques, some near breakaway so stick-slip is exercised.
        scale = 0.2 if k % 400 < 300 else 2e-4
        torque = tuple(rng.uniform(-scale, scale) for _ in range(3))
        plant.step(torque, DT)
        history.append((plant.time, *plant.position, *plant.velocity))
    return history


def test_deterministic_bit_identical_histories() -> None:
    first = _run(7)
    second = _run(7)
    assert first == second
    assert any(h[4] != 0.0 for h in first)


def test_constructor_and_step_refuse_bad_input() -> None:
    with pytest.raises(ValueError):
        ThreeAxisPlant(AXES[:2], NoCutting())
    with pytest.raises(ValueError):
        ThreeAxisPlant(AXES, NoCutting(), substeps=0)
    with pytest.raises(ValueError):
        ThreeAxisPlant(AXES, NoCutting(), max_torque=(1.0, 0.0, 1.0))
    with pytest.raises(ValueError):
        ThreeAxisPlant(AXES, NoCutting(), initial_position=(0.0, math.nan, 0.0))
    plant = ThreeAxisPlant(AXES, NoCutting())
    with pytest.raises(ValueError):
        plant.step((0.0, 0.0, 0.0), 0.0)
    with pytest.raises(ValueError):
        plant.step((0.0, 0.0), DT)


def test_time_and_cutting_force_follow_the_state() -> None:
    kline = KlineCuttingForce()
    plant = ThreeAxisPlant(AXES, kline, initial_position=(-0.05, -0.06, -0.005), start_time=2.0)
    _set_velocity(plant, (0.0, 0.003, 0.0))
    assert plant.time == 2.0
    assert plant.cutting_force() == kline.force(2.0, plant.position, plant.velocity)
    plant.step((0.0, 0.1, 0.0), DT)
    assert plant.time == pytest.approx(2.001, abs=1e-15)
    assert plant.cutting_force() == kline.force(plant.time, plant.position, plant.velocity)
