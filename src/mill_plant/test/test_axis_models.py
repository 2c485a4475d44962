"""Per-axis models: rigid (gravity, load), flexible, transfer function, velocity drive."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import scipy.linalg
import scipy.signal
from mill_common.parameters import ParameterError
from mill_models.axis_data import BELTRAN_TABLE1, RigidAxisParams
from mill_plant.axis_plant import AxisPlant
from mill_plant.cutting import NoCutting, StepForce, StepParams
from mill_plant.models.base import AxisModel
from mill_plant.models.flexible import FlexibleAxisModel, FlexibleModelParams
from mill_plant.models.rigid import RigidAxisModel, RigidModelParams
from mill_plant.models.transfer_function import TransferFunctionAxisModel, TransferFunctionParams
from mill_plant.models.velocity_drive import VelocityDriveAxisModel

MODELS = (RigidAxisModel, FlexibleAxisModel, TransferFunctionAxisModel, VelocityDriveAxisModel)


def _single(model: AxisModel, cutting=None, **kw) -> AxisPlant:
    """Model on x; y, z rigid and idle."""
    rest = [RigidAxisModel.from_parameters(i, {}) for i in (1, 2)]
    return AxisPlant([model, *rest], cutting or NoCutting(), **kw)


# ---- interface -------------------------------------------------------------------


@pytest.mark.parametrize('cls', MODELS)
def test_interface_and_defaults(cls) -> None:
    assert cls.INPUT_UNIT in ('N·m', 'V')
    names = [s.name for s in cls.PARAMETERS]
    assert len(names) == len(set(names))
    for axis in range(3):
        for gravity in (False, True):
            model = cls.from_parameters(axis, {}, gravity=gravity)
            assert isinstance(model, AxisModel)
            state = model.initial_state(0.0123)
            assert len(state) == 2 * cls.N_DOF
            assert model.position(state) == pytest.approx(0.0123, rel=1e-15)
            assert model.velocity(state) == 0.0
            assert model.input_gain() > 0.0
    with pytest.raises(ValueError, match='axis'):
        cls.from_parameters(3, {})
    with pytest.raises(ParameterError, match=f'{cls.PREFIX}.nonsense'):
        cls.from_parameters(0, {'nonsense': 1.0})


@pytest.mark.parametrize(
    ('cls', 'name', 'value'),
    [
        (RigidAxisModel, 'mass', [1.0, -2.0, 3.0]),
        (RigidAxisModel, 'pitch', [0.003, 0.003]),
        (RigidAxisModel, 'coulomb_friction', [0.3, math.nan, 0.3]),
        (FlexibleAxisModel, 'coupling_stiffness', 0.0),
        (FlexibleAxisModel, 'guide_damping', -1.0),
        (TransferFunctionAxisModel, 'dead_time', -0.001),
        (TransferFunctionAxisModel, 'force_constant', 'big'),
        (VelocityDriveAxisModel, 'inertia', [1e-3, 0.0, 1e-3]),
        (VelocityDriveAxisModel, 'amplifier_gain', 15.7),
    ],
)
def test_bad_parameters_name_the_parameter(cls, name, value) -> None:
    with pytest.raises(ParameterError, match=rf'{cls.PREFIX}\.{name}') as err:
        cls.from_parameters(1, {name: value})
    assert err.value.name == f'{cls.PREFIX}.{name}'


# ---- rigid -----------------------------------------------------------------------


def test_rigid_defaults_are_beltran_table1_and_load_scales_the_gain() -> None:
    for i, a in enumerate('xyz'):
        model = RigidAxisModel.from_parameters(i, {})
        assert model.params == BELTRAN_TABLE1[a]
        assert model.input_gain() == BELTRAN_TABLE1[a].input_gain
        m_e = BELTRAN_TABLE1[a].effective_mass
        # acceleration per torque (no friction, at speed): drops by m_e/(m_e + Δm)
        state = [0.0, 0.01]
        before = (
            model.derivative(state, 0.1, 0.0, 1.0)[1] - model.derivative(state, 0.0, 0.0, 1.0)[1]
        )
        model.add_load(12.5)
        after = (
            model.derivative(state, 0.1, 0.0, 1.0)[1] - model.derivative(state, 0.0, 0.0, 1.0)[1]
        )
        assert after / before == pytest.approx(m_e / (m_e + 12.5), rel=1e-12)
        assert model.input_gain() == pytest.approx(
            BELTRAN_TABLE1[a].input_gain * m_e / (m_e + 12.5)
        )
    with pytest.raises(ValueError, match='mass'):
        RigidAxisModel.from_parameters(0, {}).add_load(-100.0)


def test_rigid_gravity_weight_is_the_carriage_weight_and_grows_with_the_load() -> None:
    z = RigidAxisModel.from_parameters(2, {'gravity_acceleration': 9.81}, gravity=True)
    assert z.weight == pytest.approx(22.505 * 9.81)
    # Chávez-Conde eq. (3): holding torque tau = m g a gives zero net force at rest
    assert z.stick_force([0.0, 0.0], 22.505 * 9.81 * z.params.lead, 0.0) == pytest.approx(
        0.0, abs=1e-12
    )
    z.add_load(2.0)
    assert z.weight == pytest.approx(24.505 * 9.81)
    assert RigidAxisModel.from_parameters(2, {}).weight == 0.0


@pytest.mark.parametrize('gravity', [False, True])
def test_rigid_closed_form_disturbance_is_acceleration_less_b_u(gravity: bool) -> None:
    model = RigidAxisModel.from_parameters(2, {}, gravity=gravity)
    model.add_load(3.0)
    for state, u, force, mode in (
        ([0.01, 0.002], 0.3, 40.0, 1.0),
        ([0.01, -0.002], -0.2, -15.0, -1.0),
        ([0.01, 0.0], 0.5, 10.0, 1.0),  # breaking away
        ([0.01, 0.0], 0.0, 0.1, 0.0),  # stuck: x'' = 0
    ):
        generic = AxisModel.disturbance(model, state, u, force, mode, u)  # x'' - b u
        assert model.disturbance(state, u, force, mode, u) == pytest.approx(generic, rel=1e-9)


# ---- flexible --------------------------------------------------------------------


def _rigid_of(flex: FlexibleAxisModel) -> RigidAxisModel:
    p = flex.p
    m_e, c_e = flex.rigid_equivalent()
    inertia = p.motor_inertia + p.coupling_inertia + p.screw_inertia
    params = RigidAxisParams(
        mass=p.carriage_mass,
        screw_inertia=inertia,
        pitch=p.pitch,
        cart_damping=p.guide_damping,
        screw_damping=c_e - p.guide_damping,
        coulomb_friction=p.coulomb_friction,
    )
    assert params.effective_mass == pytest.approx(m_e, rel=1e-14)
    same_on_every_axis = {k: [v] * 3 for k, v in dataclasses.asdict(params).items()}
    return RigidAxisModel(RigidModelParams(**same_on_every_axis))


def _torque_run(model: AxisModel, cutting, steps: int, dt: float) -> np.ndarray:
    plant = _single(model, cutting)
    out = []
    for k in range(steps):
        t = k * dt
        tau = 0.2 if t < 0.05 else 0.0  # go, then coast to a stop against friction
        plant.step((tau, 0.0, 0.0), dt)
        out.append((plant.position[0], plant.velocity[0]))
    return np.array(out)


@pytest.mark.parametrize('mu', [0.0, 30.0])
def test_flexible_axis_with_stiff_elements_approaches_the_rigid_axis(mu) -> None:
    cut = StepForce(StepParams(force=(0.1, 0.0, 0.0), start_time=0.1))
    dt, steps = 1e-4, 3000
    errors = []
    for k in (1e5, 1e6):
        # mu = 30 N lets friction stop the 1979 kg (m_e) axis within the run
        flex = FlexibleAxisModel(
            FlexibleModelParams(coupling_stiffness=k, screw_stiffness=k, coulomb_friction=mu)
        )
        ref = _torque_run(_rigid_of(flex), cut, steps, dt)
        errors.append(np.max(np.abs(_torque_run(flex, cut, steps, dt)[:, 0] - ref[:, 0])))
        assert flex.input_gain() == pytest.approx(_rigid_of(flex).input_gain(), rel=1e-14)
    travel = np.max(np.abs(ref[:, 0]))
    assert travel > 1e-4
    if mu == 0.0:
        # the difference is the elastic deflection: ∝ 1/k
        assert errors[0] / errors[1] == pytest.approx(10.0, rel=0.05)
        assert errors[1] < 1e-6 * travel
    else:
        # stick-slip: the carriage breaks away once the chain has wound up; slower convergence
        assert np.count_nonzero(ref[:, 1] == 0.0) > 500  # stopped and stuck at the end
        assert errors[0] > 2.0 * errors[1]
        assert errors[1] < 1e-3 * travel


def _chain_frequencies(flex: FlexibleAxisModel) -> tuple[float, float]:
    """Nonzero ω of the free undamped chain J_m -k_c- J_c -k_To- (J_T + m_c a²)."""
    p = flex.p
    i1, i2 = p.motor_inertia, p.coupling_inertia
    i3 = p.screw_inertia + p.carriage_mass / flex.n**2
    k1, k2 = p.coupling_stiffness, p.screw_stiffness
    # ω⁴ - [k1 (1/i1 + 1/i2) + k2 (1/i2 + 1/i3)] ω² + k1 k2 (i1 + i2 + i3)/(i1 i2 i3) = 0
    s = k1 * (1 / i1 + 1 / i2) + k2 * (1 / i2 + 1 / i3)
    q = k1 * k2 * (i1 + i2 + i3) / (i1 * i2 * i3)
    root = math.sqrt(s * s - 4 * q)
    return math.sqrt((s - root) / 2), math.sqrt((s + root) / 2)


def test_flexible_resonances_from_free_response_match_the_analytic_values() -> None:
    flex = FlexibleAxisModel(
        FlexibleModelParams(coulomb_friction=0.0)
    )  # paper values, friction off
    w_low, w_high = _chain_frequencies(flex)
    assert w_low / (2 * math.pi) == pytest.approx(94.2, abs=1.0)
    assert w_high / (2 * math.pi) == pytest.approx(380.0, abs=3.0)
    # mode shapes (θ1, θ2, x) of K φ = ω² M φ
    p, n = flex.p, flex.n
    m = np.diag([p.motor_inertia, p.coupling_inertia, p.screw_inertia * n * n + p.carriage_mass])
    kc, ks = p.coupling_stiffness, p.screw_stiffness
    k = kc * np.array([[1, -1, 0], [-1, 1, 0], [0, 0, 0]]) + ks * np.array(
        [[0, 0, 0], [0, 1, -n], [0, -n, n * n]]
    )
    w2, shapes = scipy.linalg.eigh(k, m)
    for w_expected, col in ((w_low, 1), (w_high, 2)):
        assert math.sqrt(w2[col]) == pytest.approx(w_expected, rel=1e-9)
        plant = _single(FlexibleAxisModel(FlexibleModelParams(coulomb_friction=0.0)))
        shape = shapes[:, col] / np.max(np.abs(shapes[:, col])) * 1e-3
        plant._state[0] = [*shape, 0.0, 0.0, 0.0]
        dt = 1e-4
        twist = []
        for _ in range(2000):
            plant.step((0.0, 0.0, 0.0), dt)
            th1, th2 = plant.states[0][:2]
            twist.append(th2 - th1)
        sig = np.array(twist)
        crossings = np.nonzero(np.diff(np.signbit(sig)))[0]
        t_cross = [(c + sig[c] / (sig[c] - sig[c + 1])) * dt for c in crossings]
        period = 2.0 * (t_cross[-1] - t_cross[0]) / (len(t_cross) - 1)
        assert 2 * math.pi / period == pytest.approx(w_expected, rel=0.02)


def test_flexible_carriage_sticks_while_the_motor_winds_up() -> None:
    plant = _single(FlexibleAxisModel())
    mu = plant.models[0].coulomb_friction
    a = 0.01 / (2 * math.pi)
    for _ in range(100):  # a quarter of breakaway: the ringing chain peaks below mu
        plant.step((0.25 * mu * a, 0.0, 0.0), 1e-3)
    assert plant.velocity[0] == 0.0 and plant.position[0] == 0.0
    assert plant.states[0][0] > 0.0  # the motor turned (the chain winds up)
    for _ in range(300):
        plant.step((3.0 * mu * a, 0.0, 0.0), 1e-3)
    assert plant.position[0] > 0.0


# ---- transfer function -----------------------------------------------------------


def _exact_delayed(model: TransferFunctionAxisModel, inputs, dt, force: float = 0.0):
    """Exact response of eq. (1) to ZOH inputs delayed by T_d, at the step ends."""
    a_, b_, c_ = model.coefficients
    ss = np.array([[0.0, 1.0], [-c_, -b_]])
    kf = model.p.force_constant
    td = model.dead_time
    events = sorted([(k * dt + td, u) for k, u in enumerate(inputs)])
    x = np.zeros(2)
    t, u_now, out = 0.0, 0.0, []
    ends = [(k + 1) * dt for k in range(len(inputs))]
    marks = sorted({*[e for e, _ in events], *ends})
    ev = dict(events)
    for mark in marks:
        h = mark - t
        if h > 0:
            aug = np.zeros((3, 3))
            aug[:2, :2] = ss
            aug[1, 2] = a_ * (u_now - force / kf)
            x = (scipy.linalg.expm(aug * h) @ np.array([*x, 1.0]))[:2]
            t = mark
        if mark in ev:
            u_now = ev[mark]
        if any(abs(mark - e) < 1e-15 for e in ends):
            out.append(x[0])
    return np.array(out)


@pytest.mark.parametrize(
    ('dead_time', 'dt'), [(0.0012, 1e-3), (0.0012, 0.7e-3), (0.002, 1e-3), (0.0, 1e-3)]
)
def test_transfer_function_step_response_with_dead_time(dead_time, dt) -> None:
    model = TransferFunctionAxisModel(TransferFunctionParams(dead_time=dead_time))
    plant = _single(model)
    steps = 400
    xs = []
    for _ in range(steps):
        plant.step((1.0, 0.0, 0.0), dt)
        xs.append(plant.position[0])
    xs = np.array(xs)
    # analytic step response of A/(s² + B s + C), delayed by T_d
    a_, b_, c_ = model.coefficients
    p1, p2 = np.roots([1.0, b_, c_])
    tau = np.maximum(dt * np.arange(1, steps + 1) - dead_time, 0.0)
    analytic = a_ / c_ * (1.0 - (p2 * np.exp(p1 * tau) - p1 * np.exp(p2 * tau)) / (p2 - p1))
    assert np.max(np.abs(xs - analytic)) <= 1e-6 * np.max(np.abs(analytic))
    assert np.all(xs[tau == 0.0] == 0.0)  # nothing moves before the dead time
    # scipy lsim on a fine grid (dead time a multiple of 1e-5 s) agrees too
    t_fine = np.arange(0.0, steps * dt, 1e-5)
    _, y, _ = scipy.signal.lsim(([a_], [1.0, b_, c_]), (t_fine >= dead_time).astype(float), t_fine)
    idx = np.round(dt * np.arange(1, steps) / 1e-5).astype(int)
    assert np.max(np.abs(xs[:-1] - y[idx])) <= 1e-4 * np.max(np.abs(analytic))


def test_transfer_function_staircase_with_fractional_dead_time_is_exact() -> None:
    model = TransferFunctionAxisModel()  # T_d = 1.2 ms
    dt = 1e-3
    inputs = [math.sin(0.37 * k) + (k % 5 == 0) for k in range(300)]
    force = 100.0
    plant = _single(model, StepForce(StepParams(force=(force, 0.0, 0.0), start_time=0.0)))
    xs = []
    for u in inputs:
        plant.step((u, 0.0, 0.0), dt)
        xs.append(plant.position[0])
    ref = _exact_delayed(model, inputs, dt, force)
    assert np.max(np.abs(np.array(xs) - ref)) <= 1e-6 * np.max(np.abs(ref))


def test_transfer_function_dc_gain_force_and_load() -> None:
    model = TransferFunctionAxisModel()
    a_mm, c_ = model.p.gain, model.p.stiffness
    plant = _single(model, StepForce(StepParams(force=(39.01, 0.0, 0.0), start_time=0.0)))
    for _ in range(2000):
        plant.step((0.5, 0.0, 0.0), 0.01)  # 20 s ≫ B/C = 0.84 s
    kf = model.p.force_constant
    # DC gain A/C [mm/V] → m/V, with the force as -F/k_f volts
    assert plant.position[0] == pytest.approx(a_mm / c_ * 1e-3 * (0.5 - 39.01 / kf), rel=1e-6)
    assert kf == pytest.approx(780.2)
    assert model.moving_mass == pytest.approx(10.0)
    model.add_load(10.0)
    assert model.coefficients == pytest.approx((78.02 / 2, 163.0 / 2, 193.3 / 2))
    assert model.input_gain() == pytest.approx(78.02 / 2)
    fall = TransferFunctionAxisModel(gravity=True)
    assert fall.derivative([0.0, 0.0], 0.0, 0.0, 1.0)[1] == pytest.approx(-9.80665)


# ---- velocity drive --------------------------------------------------------------


@pytest.mark.parametrize('axis', [0, 1])
def test_velocity_drive_steady_speed_and_force(axis) -> None:
    model = VelocityDriveAxisModel.from_parameters(axis, {})
    ka, kt, b, pitch = 15.7311, 1.39, 14e-4, 0.012
    r = pitch / (2 * math.pi)
    u = 0.002
    speeds = []
    for force in (0.0, 2.0):
        others = [RigidAxisModel.from_parameters(i, {}) for i in range(3) if i != axis]
        models = [*others]
        models.insert(axis, model)
        fc = [0.0, 0.0, 0.0]
        fc[axis] = force
        plant = AxisPlant(models, StepForce(StepParams(force=fc, start_time=0.0)))
        cmd = [0.0, 0.0, 0.0]
        cmd[axis] = u
        for _ in range(1000):
            plant.step(cmd, 0.05)  # 50 s ≫ J/B = 2.1 s (x), 2.7 s (y)
        speeds.append(plant.velocity[axis])
    # Hatwesh eq. (1)-(3): ω = K_t K_a u / B at steady state, x' = r_g ω
    assert speeds[0] == pytest.approx(ka * kt / b * r * u, rel=1e-6)
    # a cutting force F is a load torque r_g F: lowers the speed by r_g² F / B
    assert speeds[1] == pytest.approx(speeds[0] - r * r * 2.0 / b, rel=1e-6)
    assert speeds[1] < speeds[0]
    assert model.steady_speed(u, 2.0) == pytest.approx(speeds[1], rel=1e-6)


def test_velocity_drive_table1_load_and_gravity() -> None:
    x, y, z = (VelocityDriveAxisModel.from_parameters(i, {}) for i in range(3))
    assert (x.inertia, y.inertia, z.inertia) == (2.8828e-3, 3.8028e-3, 3.8028e-3)
    r = 0.012 / (2 * math.pi)
    assert x.input_gain() == pytest.approx(r * 15.7311 * 1.39 / 2.8828e-3)
    x.add_load(50.0)  # Hatwesh eq. (4): J += m r_g²
    assert x.inertia == pytest.approx(2.8828e-3 + 50.0 * r * r)
    zg = VelocityDriveAxisModel.from_parameters(2, {'carried_mass': [0, 0, 80.0]}, gravity=True)
    hold = 80.0 * 9.80665 * r / (15.7311 * 1.39)
    assert zg.derivative([0.0, 0.0], hold, 0.0, 1.0)[1] == pytest.approx(0.0, abs=1e-9)
    assert zg.derivative([0.0, 0.0], 0.0, 0.0, 1.0)[1] < 0.0
