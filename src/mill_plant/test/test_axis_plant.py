"""AxisPlant: cross-validation with ThreeAxisPlant, load change, faults, mixed models."""

from __future__ import annotations

import math

import pytest
from mill_models.axis_data import BELTRAN_TABLE1
from mill_plant.axis_plant import AxisPlant, StepReport
from mill_plant.cutting import NoCutting, StepForce
from mill_plant.kline_force import KlineCuttingForce
from mill_plant.models.flexible import FlexibleAxisModel
from mill_plant.models.rigid import RigidAxisModel
from mill_plant.models.transfer_function import TransferFunctionAxisModel
from mill_plant.models.velocity_drive import VelocityDriveAxisModel
from mill_plant.three_axis import ThreeAxisPlant

AXES = [BELTRAN_TABLE1[a] for a in 'xyz']
DT = 1e-3


def _rigid(gravity_z: bool = False) -> list[RigidAxisModel]:
    return [RigidAxisModel.from_parameters(i, {}, gravity=(gravity_z and i == 2)) for i in range(3)]


def _pd(plant, ref: tuple[float, float, float], w: float = 30.0) -> tuple[float, float, float]:
    """PD torque with nominal b (Beltrán eq. (5)), poles at -w (double)."""
    out = []
    for i, axis in enumerate(AXES):
        e = ref[i] - plant.position[i]
        out.append((w * w * e - 2.0 * w * plant.velocity[i]) / axis.input_gain)
    return (out[0], out[1], out[2])


@pytest.mark.parametrize('cutting', ['kline', 'step'])
def test_three_rigid_models_reproduce_three_axis_plant(cutting: str) -> None:
    start = (-0.075, -0.105, -0.005)

    def force():  # a Kline model learns its plant's path: one per plant
        if cutting == 'kline':
            return KlineCuttingForce()
        return StepForce((40.0, -25.0, 10.0), start_time=0.5)

    old = ThreeAxisPlant(AXES, force(), start, max_torque=(0.5, 0.5, 0.5))
    new = AxisPlant(_rigid(), force(), start, max_input=(0.5, 0.5, 0.5))
    sliding = stuck = 0
    for k in range(2000):  # 2 s: a 3 mm/s cut in x, then hold (stick-slip at the stop)
        t = k * DT
        ref = (start[0] + 0.003 * min(t, 1.2), start[1], start[2])
        u = _pd(old, ref)
        r_old = old.step(u, DT)
        r_new = new.step(u, DT)
        assert r_old == r_new
        assert old.position == new.position and old.velocity == new.velocity  # bit-identical
        sliding += sum(v != 0.0 for v in old.velocity)
        stuck += sum(v == 0.0 for v in old.velocity)
        assert old.disturbance(u) == new.disturbance(u)
    assert sliding > 1000 and stuck > 10  # both friction regimes were exercised
    assert new.cutting_force() == old.cutting_force()
    assert new.time == old.time


class _RigidViaModelCalls(RigidAxisModel):
    """The rigid model as any other model: a subclass takes the plant's general path."""


def test_rigid_scalar_path_equals_the_general_path_bit_for_bit() -> None:
    start = (-0.075, -0.105, -0.005)

    def plant(cls: type[RigidAxisModel]) -> AxisPlant:
        models = [cls.from_parameters(i, {}, gravity=(i == 2)) for i in range(3)]
        # chip and depth from the tool's path: the model learns every accepted state
        kline = KlineCuttingForce(specific_energy=1e8)
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
    return AxisPlant(models, StepForce((30.0, -20.0, 15.0), start_time=0.05), **kw)


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
        plant = AxisPlant(models, StepForce((30.0, -20.0, 15.0), start_time=0.05))
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
    faulty = AxisPlant(models, StepForce((0.5, -0.7, 1.0), start_time=0.002))
    clean = AxisPlant(models, StepForce((0.5, -0.7, 1.0), start_time=0.002))
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
        [tf, VelocityDriveAxisModel(), FlexibleAxisModel(coulomb_friction=0.0)],
        StepForce((50.0, 20.0, 5.0)),
    )
    for _ in range(7):
        plant.step((1.0, 0.5, 0.2), 0.4e-3)  # 2.8 ms: the delayed 1 V acts since 1.2 ms
    xi = plant.disturbance((2.0, 0.5, 0.2))
    x, v = plant.states[0]
    a, b, c = plant.models[0].coefficients
    # Maharof eq. (1): x'' = -B v - C x + A (u(t - T_d) - F/k_f); xi = x'' - A u_now
    expected = -b * v - c * x + a * (1.0 - 50.0 / tf.p['force_constant']) - a * 2.0
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
