"""AxisPlant: RK4 against DOP853, stick-slip, brake, clipping, disturbance, load change,
mixed models, determinism; the scalar path of three rigid axes against the general path."""

from __future__ import annotations

import itertools
import math
import random

import numpy as np
import pytest
from mill_models.axis_data import BELTRAN_TABLE1
from mill_plant.axis_plant import AxisPlant, StepReport
from mill_plant.cutting import NoCutting, StepForce, StepParams
from mill_plant.kline_force import KlineCuttingForce, KlineParams
from mill_plant.models.flexible import FlexibleAxisModel, FlexibleModelParams
from mill_plant.models.rigid import RigidAxisModel
from mill_plant.models.transfer_function import TransferFunctionAxisModel
from mill_plant.models.velocity_drive import VelocityDriveAxisModel
from scipy.integrate import solve_ivp

AXES = [BELTRAN_TABLE1[a] for a in 'xyz']
DT = 1e-3


def _rigid(gravity_z: bool = False) -> list[RigidAxisModel]:
    return [RigidAxisModel.from_parameters(i, {}, gravity=(gravity_z and i == 2)) for i in range(3)]


def _set_velocity(plant: AxisPlant, velocity: tuple[float, float, float]) -> None:
    """Start rigid axes moving: the plant has no public state setter, and tests need one."""
    for state, v in zip(plant._state, velocity, strict=True):
        state[1] = v


def _pd(plant, ref: tuple[float, float, float], w: float = 30.0) -> tuple[float, float, float]:
    """PD torque with nominal b (Beltrán eq. (5)), poles at -w (double)."""
    out = []
    for i, axis in enumerate(AXES):
        e = ref[i] - plant.position[i]
        out.append((w * w * e - 2.0 * w * plant.velocity[i]) / axis.input_gain)
    return (out[0], out[1], out[2])


# ---- three rigid axes: accuracy, stick-slip, brake, clipping, disturbance ---------------


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
        KlineParams(specific_energy=specific_energy, helix_angle=helix_deg, workpiece_top=-0.0048)
    )
    x0 = (-0.06, -0.08, -0.005)
    v0 = (0.01, 0.01, -0.0002)
    plant = AxisPlant(_rigid(), kline, initial_position=x0, substeps=4)
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
    plant = AxisPlant(_rigid(), NoCutting(), initial_position=x0)
    torque = tuple(
        0.95 * a.coulomb_friction * a.lead * s for a, s in zip(AXES, (1, -1, 1), strict=True)
    )
    for _ in range(1000):
        plant.step(torque, DT)
        assert plant.velocity == (0.0, 0.0, 0.0)
        assert plant.position == x0


def test_stiction_holds_against_a_sub_breakaway_cutting_force() -> None:
    plant = AxisPlant(_rigid(), StepForce(StepParams(force=(0.2, -0.25, 0.29), start_time=0.0)))
    for _ in range(100):
        plant.step((0.0, 0.0, 0.0), DT)
    assert plant.velocity == (0.0, 0.0, 0.0)
    assert plant.position == (0.0, 0.0, 0.0)
    # ...and a force above mu moves the axis against it (here -x).
    moved = AxisPlant(_rigid(), StepForce(StepParams(force=(0.31, 0.0, 0.0), start_time=0.0)))
    for _ in range(100):
        moved.step((0.0, 0.0, 0.0), DT)
    assert moved.velocity[0] < 0.0 and moved.position[0] < 0.0


def test_just_above_breakaway_moves() -> None:
    plant = AxisPlant(_rigid(), NoCutting())
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
    plant = AxisPlant(_rigid(), NoCutting())
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


def test_non_finite_torque_brakes_only_that_rigid_axis() -> None:
    start = (0.01, 0.02, -0.003)
    faulty = AxisPlant(
        _rigid(), StepForce(StepParams(force=(0.5, -0.7, 1.0), start_time=0.002)), start
    )
    clean = AxisPlant(
        _rigid(), StepForce(StepParams(force=(0.5, -0.7, 1.0), start_time=0.002)), start
    )
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


def test_torque_is_clipped_and_reported_on_rigid_axes() -> None:
    limited = AxisPlant(_rigid(), NoCutting(), max_input=(0.1, 0.2, math.inf))
    reference = AxisPlant(_rigid(), NoCutting())
    report = limited.step((0.5, -0.15, 7.0), DT)
    reference.step((0.1, -0.15, 7.0), DT)
    assert report == StepReport((True, False, False), (False, False, False), (0.1, -0.15, 7.0))
    assert limited.position == reference.position
    assert limited.velocity == reference.velocity
    assert limited.step((-1.0, 0.0, 0.0), DT).applied_torque == (-0.1, 0.0, 0.0)


def test_disturbance_of_sliding_axes_without_cutting() -> None:
    plant = AxisPlant(_rigid(), NoCutting())
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
    plant = AxisPlant(_rigid(), StepForce(StepParams(force=force, start_time=0.01)))
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
    plant = AxisPlant(_rigid(), NoCutting())
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
    plant = AxisPlant(
        _rigid(),
        KlineCuttingForce(),
        initial_position=(-0.075, -0.105, -0.005),
        max_input=(0.5, 0.5, 0.5),
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


def test_time_and_cutting_force_follow_the_state() -> None:
    kline = KlineCuttingForce()
    plant = AxisPlant(_rigid(), kline, initial_position=(-0.05, -0.06, -0.005), start_time=2.0)
    _set_velocity(plant, (0.0, 0.003, 0.0))
    assert plant.time == 2.0
    assert plant.cutting_force() == kline.force(2.0, plant.position, plant.velocity)
    plant.step((0.0, 0.1, 0.0), DT)
    assert plant.time == pytest.approx(2.001, abs=1e-15)
    assert plant.cutting_force() == kline.force(plant.time, plant.position, plant.velocity)


# ---- the scalar path, load change, faults and mixed models -------------------------------


class _RigidViaModelCalls(RigidAxisModel):
    """The rigid model as any other model: a subclass takes the plant's general path."""


def test_rigid_scalar_path_equals_the_general_path_bit_for_bit() -> None:
    start = (-0.075, -0.105, -0.005)

    def plant(cls: type[RigidAxisModel]) -> AxisPlant:
        models = [cls.from_parameters(i, {}, gravity=(i == 2)) for i in range(3)]
        # chip and depth from the tool's path: the model learns every accepted state
        kline = KlineCuttingForce(KlineParams(specific_energy=1e8))
        return AxisPlant(
            models,
            kline,
            start,
            max_input=(0.5, 0.5, 0.12),  # z: too weak to hold the load added at 0.8 s
            load_change_time=0.8,
            load_change_mass=(4.0, 0.0, 2.5),
        )

    fast, general = plant(RigidAxisModel), plant(_RigidViaModelCalls)
    assert fast._rigid and not general._rigid
    hold_z = AXES[2].mass * 9.80665 * AXES[2].lead
    stuck = [0, 0, 0]
    braked = 0
    saturated = [0, 0, 0]
    for k in range(1500):
        t = k * DT
        ref = (start[0] + 0.003 * min(t, 1.2), start[1] + 0.002 * min(t, 0.6), start[2])
        u = list(_pd(fast, ref))
        u[2] += hold_z
        if k % 250 < 10:
            u[k % 3] = math.nan
        # repr: exact for floats, and NaN (a braked axis) equals NaN
        assert repr(fast.disturbance(u)) == repr(general.disturbance(u))
        report = fast.step(u, DT)
        assert report == general.step(u, DT)
        assert fast.states == general.states
        assert fast.cutting_force() == general.cutting_force()
        stuck = [n + (v == 0.0) for n, v in zip(stuck, fast.velocity, strict=True)]
        braked += any(report.faulted)
        saturated = [n + c for n, c in zip(saturated, report.saturated, strict=True)]
    assert fast.load_changed and general.load_changed
    # every path was taken: stuck and sliding axes, braked ones, a clipped one
    assert min(stuck) > 10 and braked == 60 and saturated[2] > 100


def _mixed(**kw) -> AxisPlant:
    models = [
        TransferFunctionAxisModel.from_parameters(0, {}),
        VelocityDriveAxisModel.from_parameters(1, {}),
        RigidAxisModel.from_parameters(2, {}, gravity=True),
    ]
    return AxisPlant(
        models, StepForce(StepParams(force=(30.0, -20.0, 15.0), start_time=0.05)), **kw
    )


def _drive(plant: AxisPlant, steps: int, dt: float = DT) -> list[tuple[float, ...]]:
    out = []
    for k in range(steps):
        t = plant.time
        u = (0.01 * math.sin(20.0 * t), 0.002 * math.cos(13.0 * t), 0.0433 + 0.01 * (k % 7 == 0))
        plant.step(u, dt)
        out.append((plant.time, *plant.position, *plant.velocity))
    return out


def test_mixed_models_run_deterministically_and_each_axis_matches_its_own_plant() -> None:
    first = _drive(_mixed(), 500)
    assert first == _drive(_mixed(), 500)  # bit-identical
    # StepForce depends on time only: the axes are uncoupled, so each axis equals a plant
    # where the other two axes are rigid (no dead-time splits for them).
    solo = [
        [TransferFunctionAxisModel(), *_rigid()[1:]],
        [_rigid()[0], VelocityDriveAxisModel.from_parameters(1, {}), _rigid()[2]],
        _rigid(gravity_z=True),
    ]
    for i, models in enumerate(solo):
        plant = AxisPlant(models, StepForce(StepParams(force=(30.0, -20.0, 15.0), start_time=0.05)))
        ref = _drive(plant, 500)
        for a, b in zip(first, ref, strict=True):
            assert abs(a[1 + i] - b[1 + i]) <= 1e-12
            assert abs(a[4 + i] - b[4 + i]) <= 1e-9
    assert all(math.isfinite(v) for v in first[-1])


def test_load_change_happens_at_the_first_step_at_or_after_its_time() -> None:
    dt = 2.0**-10
    mass = (3.0, 5.0, 7.0)
    for change_time, first_step in ((8 * dt, 8), (7.5 * dt, 8), (0.0, 0)):
        sched = AxisPlant(
            _rigid(), NoCutting(), load_change_time=change_time, load_change_mass=mass
        )
        manual = AxisPlant(_rigid(), NoCutting())
        gains = [m.input_gain() for m in sched.models]
        for k in range(12):
            if k == first_step:
                for model, m in zip(manual.models, mass, strict=True):
                    model.add_load(m)
            assert sched.load_changed == (k > first_step)
            u = (0.05, -0.05, 0.05)
            sched.step(u, dt)
            manual.step(u, dt)
            assert sched.position == manual.position and sched.velocity == manual.velocity
            assert sched.load_changed == (k >= first_step)
            if k == first_step - 1:
                assert sched.models[0].input_gain() == gains[0]
        for i, axis in enumerate(AXES):
            m_e = axis.effective_mass
            assert sched.models[i].input_gain() == pytest.approx(
                gains[i] * m_e / (m_e + mass[i]), rel=1e-14
            )
    # The plant works on copies: the caller's models are not loaded.
    mine = _rigid()
    plant = AxisPlant(mine, NoCutting(), load_change_time=0.0, load_change_mass=mass)
    plant.step((0.0, 0.0, 0.0), dt)
    assert mine[0].input_gain() == AXES[0].input_gain


def test_non_finite_input_brakes_only_that_axis_of_any_model() -> None:
    models = [TransferFunctionAxisModel(), FlexibleAxisModel(), VelocityDriveAxisModel()]
    faulty = AxisPlant(models, StepForce(StepParams(force=(0.5, -0.7, 1.0), start_time=0.002)))
    clean = AxisPlant(models, StepForce(StepParams(force=(0.5, -0.7, 1.0), start_time=0.002)))
    u = (0.2, 0.5, 0.1)
    for _ in range(30):
        faulty.step(u, DT)
        clean.step(u, DT)
    for axis in range(3):
        held = faulty.position[axis]
        held_state = faulty.states[axis]
        bad = list(u)
        bad[axis] = math.nan
        report = faulty.step(bad, DT)
        clean.step(u, DT)
        assert report.faulted == tuple(i == axis for i in range(3))
        assert report.applied_torque[axis] == 0.0
        assert faulty.velocity[axis] == 0.0
        assert faulty.position[axis] == held
        n = len(held_state) // 2
        assert faulty.states[axis][:n] == held_state[:n]
        assert all(v == 0.0 for v in faulty.states[axis][n:])
        assert math.isnan(faulty.disturbance(bad)[axis])
        for other in range(3):
            if other != axis and axis == 0:  # before any other axis was braked
                assert faulty.position[other] == clean.position[other]
    faulty.step(u, DT)
    assert all(v != 0.0 for v in faulty.velocity)  # recovers


def test_input_is_clipped_and_reported_in_the_model_unit() -> None:
    models = [
        TransferFunctionAxisModel(),
        VelocityDriveAxisModel(),
        RigidAxisModel.from_parameters(2, {}),
    ]
    limited = AxisPlant(models, NoCutting(), max_input=(10.0, 10.0, 0.5))
    reference = AxisPlant(models, NoCutting())
    report = limited.step((12.0, -3.0, -0.7), DT)
    reference.step((10.0, -3.0, -0.5), DT)
    assert report == StepReport((True, False, True), (False, False, False), (10.0, -3.0, -0.5))
    assert limited.position == reference.position
    assert limited.velocity == reference.velocity


def test_gravity_sags_a_rigid_z_axis_and_the_holding_torque_holds_it() -> None:
    z = AXES[2]
    plant = AxisPlant(_rigid(gravity_z=True), NoCutting(), (0.0, 0.0, 0.1))
    for _ in range(200):
        plant.step((0.0, 0.0, 0.0), DT)
    # Chávez-Conde eq. (3): m_e z'' + c_e z' = -m g + mu (sliding down), from rest
    force = -z.mass * 9.80665 + z.coulomb_friction
    rate = z.effective_damping / z.effective_mass
    t = plant.time
    v = force / z.effective_damping * (1.0 - math.exp(-rate * t))
    dz = force / z.effective_damping * (t - (1.0 - math.exp(-rate * t)) / rate)
    assert plant.velocity[2] == pytest.approx(v, rel=1e-9)
    assert plant.position[2] - 0.1 == pytest.approx(dz, rel=1e-9)
    assert plant.position[2] < 0.1
    assert plant.position[:2] == (0.0, 0.0)

    hold = z.mass * 9.80665 * z.lead  # tau = m g a
    for extra in (0.0, 0.9 * z.coulomb_friction * z.lead, -0.9 * z.coulomb_friction * z.lead):
        held = AxisPlant(_rigid(gravity_z=True), NoCutting(), (0.0, 0.0, 0.1))
        for _ in range(200):
            held.step((0.0, 0.0, hold + extra), DT)
        assert held.position[2] == 0.1 and held.velocity[2] == 0.0


def test_disturbance_of_internal_state_models() -> None:
    tf = TransferFunctionAxisModel()
    plant = AxisPlant(
        [
            tf,
            VelocityDriveAxisModel(),
            FlexibleAxisModel(FlexibleModelParams(coulomb_friction=0.0)),
        ],
        StepForce(StepParams(force=(50.0, 20.0, 5.0), start_time=0.0)),
    )
    for _ in range(7):
        plant.step((1.0, 0.5, 0.2), 0.4e-3)  # 2.8 ms: the delayed 1 V acts since 1.2 ms
    xi = plant.disturbance((2.0, 0.5, 0.2))
    x, v = plant.states[0]
    a, b, c = plant.models[0].coefficients
    # Maharof eq. (1): x'' = -B v - C x + A (u(t - T_d) - F/k_f); xi = x'' - A u_now
    expected = -b * v - c * x + a * (1.0 - 50.0 / tf.p.force_constant) - a * 2.0
    assert xi[0] == pytest.approx(expected, rel=1e-12)
    # Consistency with the motion over a short step for the non-delayed models
    before = plant.velocity
    gains = [m.input_gain() for m in plant.models]
    plant.step((2.0, 0.5, 0.2), 1e-7)
    for i in (1, 2):
        accel = (plant.velocity[i] - before[i]) / 1e-7
        assert accel == pytest.approx(gains[i] * (0.5, 0.2)[i - 1] + xi[i], rel=1e-4)


def test_constructor_and_step_refuse_bad_input() -> None:
    with pytest.raises(ValueError, match='models'):
        AxisPlant(_rigid()[:2], NoCutting())
    with pytest.raises(ValueError, match='models'):
        AxisPlant([*_rigid()[:2], AXES[2]], NoCutting())
    with pytest.raises(ValueError, match='substeps'):
        AxisPlant(_rigid(), NoCutting(), substeps=0)
    with pytest.raises(ValueError, match='max_input'):
        AxisPlant(_rigid(), NoCutting(), max_input=(1.0, 0.0, 1.0))
    with pytest.raises(ValueError, match='initial_position'):
        AxisPlant(_rigid(), NoCutting(), initial_position=(0.0, math.nan, 0.0))
    with pytest.raises(ValueError, match='load_change_time'):
        AxisPlant(_rigid(), NoCutting(), load_change_time=math.nan)
    with pytest.raises(ValueError, match='load_change_mass'):
        AxisPlant(_rigid(), NoCutting(), load_change_mass=(0.0, math.inf, 0.0))
    plant = AxisPlant(
        _rigid(), NoCutting(), load_change_time=0.0, load_change_mass=(5.0, -30.0, 0.0)
    )
    with pytest.raises(ValueError, match='mass'):
        plant.step((0.0, 0.0, 0.0), DT)  # y: 23.896 kg - 30 kg
    assert plant.models[0].input_gain() == AXES[0].input_gain  # all or nothing
    assert not plant.load_changed
    plant = AxisPlant(_rigid(), NoCutting())
    with pytest.raises(ValueError, match='dt'):
        plant.step((0.0, 0.0, 0.0), 0.0)
    with pytest.raises(ValueError, match='input'):
        plant.step((0.0, 0.0), DT)
