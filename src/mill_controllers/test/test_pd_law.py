"""PD law of Beltrán 2013 eq. (9)-(12): gains, compensation, clipping, bad inputs."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mill_common.parameters import ParameterError
from mill_common.signals import AxisReference, ControlInputs, Estimate
from mill_controllers.base import AxisController
from mill_controllers.pd_law import AdrcController, PdController, PdGains

B = 20.96  # [(m/s²)/(N·m)], the x axis of Beltrán 2013 Table 1


def _closed_loop_matrix(ctrl: AxisController, xi: float, ref: AxisReference) -> np.ndarray:
    """Error dynamics [e, ė]' = A·[e, ė] of ẍ = b·τ + ξ under ctrl, with exact ξ̂ and v̂.

    The law is affine in (e, ė), so two probes plus the origin give A exactly.
    """

    def error_accel(e: float, de: float) -> float:
        y = ref.position + e
        est = Estimate(y, ref.velocity + de, xi)
        tau = ctrl.compute(ControlInputs(0.0, y, ref, est))
        return B * tau + xi - ref.acceleration  # ë = ẍ − ẍ*

    a0 = error_accel(0.0, 0.0)
    return np.array([[0.0, 1.0], [error_accel(1.0, 0.0) - a0, error_accel(0.0, 1.0) - a0]])


@pytest.mark.parametrize(('omega', 'zeta'), [(12.0, 0.7071), (30.0, 0.3), (5.0, 0.95)])
def test_closed_loop_poles_are_the_designed_ones(omega: float, zeta: float) -> None:
    ctrl = AdrcController(B, 1e-3, PdGains(omega_c=omega, zeta_c=zeta, torque_limit=math.inf))
    ref = AxisReference(0.02, 0.003, 0.1)
    xi = -3.6
    a = _closed_loop_matrix(ctrl, xi, ref)
    got = np.sort_complex(np.linalg.eigvals(a))
    wd = omega * math.sqrt(1.0 - zeta**2)
    want = np.sort_complex(np.array([-zeta * omega - 1j * wd, -zeta * omega + 1j * wd]))
    np.testing.assert_allclose(got, want, rtol=1e-9)
    # With exact ξ̂ the origin is an equilibrium: the disturbance is fully rejected.
    y = ref.position
    tau = ctrl.compute(ControlInputs(0.0, y, ref, Estimate(y, ref.velocity, xi)))
    assert B * tau + xi == pytest.approx(ref.acceleration, abs=1e-12)


def test_gains_fix_the_eq12_misprint() -> None:
    ctrl = AdrcController(B, 1e-3)
    assert ctrl.alpha1 == pytest.approx(2 * 0.7071 * 12.0)
    assert ctrl.alpha0 == pytest.approx(144.0)  # ω_c², not ω_c as printed


def test_pd_variant_ignores_the_disturbance_estimate() -> None:
    ref = AxisReference(0.0, 0.0, 0.0)
    pd = PdController(B, 1e-3, PdGains(torque_limit=math.inf))
    adrc = AdrcController(B, 1e-3, PdGains(torque_limit=math.inf))
    est0 = Estimate(0.001, 0.002, 0.0)
    est1 = Estimate(0.001, 0.002, 5.0)
    assert pd.compute(ControlInputs(0.0, 0.001, ref, est1)) == pd.compute(
        ControlInputs(0.0, 0.001, ref, est0)
    )
    assert adrc.compute(ControlInputs(0.0, 0.001, ref, est1)) == pytest.approx(
        adrc.compute(ControlInputs(0.0, 0.001, ref, est0)) - 5.0 / B
    )
    # A NaN ξ̂ is not read by the PD variant, so it is not an error there.
    assert math.isfinite(
        pd.compute(ControlInputs(0.0, 0.001, ref, Estimate(0.001, 0.002, math.nan)))
    )
    # Same law otherwise: both use the observer's velocity, not the reference's.
    assert pd.compute(ControlInputs(0.0, 0.0, ref, Estimate(0.0, 0.01, 0.0))) == pytest.approx(
        -pd.alpha1 * 0.01 / B
    )


def test_pd_leaves_the_static_error_xi_over_omega_squared() -> None:
    # The uncompensated law has the steady error e = ξ/α0 (the paper's figs. 5-7 effect).
    pd = PdController(B, 1e-3, PdGains(torque_limit=math.inf))
    ref = AxisReference(0.0, 0.0, 0.0)
    xi = -3.6
    e = xi / pd.alpha0
    tau = pd.compute(ControlInputs(0.0, e, ref, Estimate(e, 0.0, xi)))
    assert B * tau + xi == pytest.approx(0.0, abs=1e-12)


def test_output_is_clipped() -> None:
    ctrl = AdrcController(B, 1e-3, PdGains(torque_limit=0.5))
    ref = AxisReference(0.0, 0.0, 0.0)
    assert ctrl.compute(ControlInputs(0.0, -1.0, ref, Estimate(-1.0, 0.0, 0.0))) == 0.5
    assert ctrl.compute(ControlInputs(0.0, 1.0, ref, Estimate(1.0, 0.0, 0.0))) == -0.5
    small = ctrl.compute(ControlInputs(0.0, 1e-5, ref, Estimate(1e-5, 0.0, 0.0)))
    assert small == pytest.approx(-144.0 * 1e-5 / B)


@pytest.mark.parametrize('cls', [AdrcController, PdController])
@pytest.mark.parametrize(
    'field', ['t', 'y', 'position', 'velocity', 'acceleration', 'v_hat', 'xi_hat']
)
@pytest.mark.parametrize('bad', [math.nan, math.inf, -math.inf])
def test_non_finite_inputs_raise(cls: type, field: str, bad: float) -> None:
    ctrl = cls(B, 1e-3)
    args = {'t': 0.0, 'y': 0.0}
    ref = {'position': 0.0, 'velocity': 0.0, 'acceleration': 0.0}
    est = {'v_hat': 0.0, 'xi_hat': 0.0}
    for group in (args, ref, est):
        if field in group:
            group[field] = bad
    inputs = ControlInputs(
        args['t'], args['y'], AxisReference(**ref), Estimate(0.0, est['v_hat'], est['xi_hat'])
    )
    call = lambda: ctrl.compute(inputs)  # noqa: E731
    if cls is PdController and field == 'xi_hat':
        assert call() == 0.0
    else:
        with pytest.raises(ValueError, match='non-finite'):
            call()


@pytest.mark.parametrize('cls', [AdrcController, PdController])
def test_parameters(cls: type) -> None:
    assert cls.PREFIX == 'pd'
    defaults = {p.name: p.default for p in cls.PARAMETERS}
    assert defaults == {'omega_c': 12.0, 'zeta_c': 0.7071, 'torque_limit': 5.0}
    assert all(p.description for p in cls.PARAMETERS)
    ctrl = cls.from_parameters(B, 1e-3, {'omega_c': 20, 'torque_limit': math.inf})
    assert ctrl.alpha0 == pytest.approx(400.0)
    assert ctrl.torque_limit == math.inf
    assert isinstance(ctrl, AxisController)


@pytest.mark.parametrize('name', ['omega_c', 'zeta_c', 'torque_limit'])
@pytest.mark.parametrize('value', [0.0, -2.0, math.nan])
def test_bad_parameters_raise_naming_them(name: str, value: float) -> None:
    with pytest.raises(ParameterError) as info:
        AdrcController.from_parameters(B, 1e-3, {name: value})
    assert info.value.name == f'pd.{name}'
    with pytest.raises(ParameterError, match=f'pd.{name}'):
        PdController(B, 1e-3, PdGains(**{name: value}))


def test_infinite_gains_are_refused_but_infinite_limit_is_not() -> None:
    with pytest.raises(ParameterError, match=r'pd\.omega_c'):
        AdrcController(B, 1e-3, PdGains(omega_c=math.inf))
    AdrcController(B, 1e-3, PdGains(torque_limit=math.inf))


@pytest.mark.parametrize('b', [0.0, math.nan, -math.inf])
def test_bad_input_gain_is_refused(b: float) -> None:
    with pytest.raises(ParameterError, match='input_gain'):
        AdrcController(b, 1e-3)


def test_a_non_finite_gain_gives_no_command_not_a_full_scale_one() -> None:
    # ω_c = 1e300: α0 = ω_c² is inf in float arithmetic; the clip must not turn inf·0 = NaN
    # into -torque_limit (the loop brakes on a non-finite command; the node refuses the gain).
    from mill_controllers.base import saturate

    ctrl = PdController(B, 1e-3, PdGains(omega_c=1e300))
    at_ref = ControlInputs(0.0, 0.0, AxisReference(0.0, 0.0, 0.0), Estimate(0.0, 0.0, 0.0))
    assert math.isnan(ctrl.compute(at_ref))
    assert [saturate(u, 5.0) for u in (7.0, -7.0, 2.5, math.inf)] == [5.0, -5.0, 2.5, 5.0]
    assert math.isnan(saturate(math.nan, 5.0))
