"""Beltrán 2013's figures computed from the model and the cores, without a run
(docs/papers.md): the constants of the readings, the closed loop's eigenvalues under both
readings of c_t, the GPI observer's response to the tooth-passing harmonics and its bias
with a straight line between samples, and the stiffnesses of the depth and of the chip."""

from __future__ import annotations

import math

import numpy as np
from mill_analysis.papers import BELTRAN_MEAN_FORCE
from mill_controllers.pd_law import PdController
from mill_models.axis_data import BELTRAN_TABLE1, RigidAxisParams
from mill_observers.chain_design import continuous_interval
from mill_observers.gpi import GpiObserver

from mill_bringup import scenario
from mill_bringup.docs_figures.runs import law_values, sig

AXES = 'xyz'
TOOTH_HZ = (60.0, 120.0)  # the tooth-passing frequency and its first harmonic


def _observer(T: float, params: dict) -> GpiObserver:
    axis = BELTRAN_TABLE1['x']  # without a command the estimate of ξ does not depend on b
    return GpiObserver.from_parameters(axis.input_gain, T, params)


def closed_loop_eigenvalues(
    axis: RigidAxisParams, c_e: float, alphas: tuple[float, float], beta: np.ndarray
) -> np.ndarray:
    """The continuous loop of eq. (1) (no friction, no force), the PD law eq. (9) with
    alphas = (α0, α1) on the observer's velocity and ξ̂, and the observer eq. (15) with
    gains β = [β6 … β0]: the
    9-state linearisation; c_e the plant's damping [N·s/m]. The law's nominal b is the
    plant's, so b·τ is the law's bracket."""
    n = 2 + len(beta)  # [x, v, x̂, v̂, ξ̂, ξ̂′ …]
    a = np.zeros((n, n))
    # τ = (1/b)(−α1 v̂ − α0 x − ξ̂) at reference 0, so b·τ is this row
    torque = np.zeros(n)
    torque[[0, 3, 4]] = -alphas[0], -alphas[1], -1.0
    a[0, 1] = 1.0
    a[1] = torque
    a[1, 1] -= c_e / axis.effective_mass
    a[2:, 3:] = np.eye(n - 2, n - 3)  # the chain of eq. (14)
    a[3] += torque
    a[2:, 0] += beta  # β (y − x̂), y = x
    a[2:, 2] -= beta
    return np.linalg.eigvals(a)


def _xi_response(obs: GpiObserver, hz: float) -> complex:
    """ξ̂/ξ of the observer core at `hz`: ẍ = sin ωt sampled, no command, the gain fitted
    over the second of two seconds (whole periods, the start transient long gone)."""
    T, w = obs.sample_period, 2 * math.pi * hz
    t = T * np.arange(round(2.0 / T))
    xi_hat = np.empty(t.size)
    for k, tk in enumerate(t):
        xi_hat[k] = obs.correct(-math.sin(w * tk) / w**2).disturbance
        obs.predict(0.0)
    late = t >= 1.0
    basis = np.column_stack([np.sin(w * t[late]), np.cos(w * t[late]), np.ones(late.sum())])
    (s, c, _), *_ = np.linalg.lstsq(basis, xi_hat[late], rcond=None)
    return complex(s, c)  # sin ωt → |G| sin(ωt + arg G)


def _line_bias(obs: GpiObserver) -> float:
    """`continuous` with the position a straight line between samples, not the parabola:
    the relative error of its estimate of a constant ξ. Under ξ constant, y = ½ξt² is a
    parabola (c = ½ξT² per period); the line adds (Γ_d − Γ_c)·c to every period, which the
    loop turns into a constant offset (I − Φ)⁻¹(Γ_d − Γ_c)·c of the scaled state, whose
    ξ component over ξ = 2c/T² (scaled: 2c) is the bias."""
    phi, _, _, g_d, g_c = continuous_interval(
        7, obs.input_gain, obs.sample_period, obs.continuous_poles()
    )
    offset = np.linalg.solve(np.eye(7) - phi, g_d - g_c)
    return float(offset[2] / 2.0)


def figures() -> dict[str, str]:
    out: dict[str, str] = {}
    scen = scenario.load('beltran')
    pd = scen.variant('pd')
    ctrl = pd.parameters('z_controller')
    T = ctrl['sample_period']
    omega_c = ctrl['pd.omega_c']
    obs_params = law_values(scen.parameters('x_observer'), 'gpi')
    for a in AXES:
        axis = BELTRAN_TABLE1[a]
        out[f'm_e.{a}'] = f'{axis.effective_mass:.2f}'  # [kg]
        out[f'b.{a}'] = f'{axis.input_gain:.2f}'  # [m/s² per N·m]
        out[f'pd_stiffness.{a}'] = f'{axis.effective_mass * omega_c**2 / 1e3:.1f}'  # [kN/m]
    law = PdController.from_parameters(
        BELTRAN_TABLE1['x'].input_gain, T, law_values(pd.parameters('x_controller'), 'pd')
    )
    out['alpha1'], out['alpha0'] = f'{law.alpha1:.2f}', f'{law.alpha0:g}'
    alphas = (law.alpha0, law.alpha1)
    obs = _observer(T, obs_params)
    beta = obs.continuous_coefficients()
    out['beta0'] = f'{beta[-1]:.1e}'.replace('e+', 'e')
    # c_t: translational (ours) or rotational, c_e = c_b + c_t/a² (the literal reading)
    out['c_e'] = f'{BELTRAN_TABLE1["x"].effective_damping:g}'
    for a in AXES:
        axis = BELTRAN_TABLE1[a]
        literal = axis.cart_damping + axis.screw_damping / axis.lead**2
        if a == 'x':  # the same pitch on every axis
            out['c_e_literal'] = f'{literal:.1e}'.replace('e+0', 'e')
        worst = closed_loop_eigenvalues(axis, literal, alphas, beta).real.max()
        out[f'literal.eigenvalue.{a}'] = f'{worst:+.0f}'  # [1/s]
    slowest = max(
        closed_loop_eigenvalues(
            BELTRAN_TABLE1[a], BELTRAN_TABLE1[a].effective_damping, alphas, beta
        ).real.max()
        for a in AXES
    )
    out['ours.eigenvalue'] = sig(slowest, 2)
    response = {hz: _xi_response(_observer(T, obs_params), hz) for hz in TOOTH_HZ}
    for hz, g in response.items():
        out[f'xi.gain.{hz:.0f}'] = sig(abs(g), 2)
    lead = response[TOOTH_HZ[0]]  # at the tooth-passing frequency [°]
    out['xi.phase.60'] = f'{math.degrees(math.atan2(lead.imag, lead.real)):.0f}'
    continuous = _observer(T, {**obs_params, 'discretisation': 'continuous'})
    out['line_bias'] = f'{-100 * _line_bias(continuous):.1f}'  # [% low]
    # F_z pushes the tool in and grows with the depth: against the z axis's PD stiffness
    plant = scen.parameters('plant')
    depth = plant['kline.workpiece_top'] - plant['kline.program'][2]  # [m]
    depth_stiffness = BELTRAN_MEAN_FORCE[2] / depth
    out['depth_stiffness'] = f'{depth_stiffness / 1e3:.1f}'  # [kN/m]
    z = BELTRAN_TABLE1['z']
    out['depth_ratio'] = f'{depth_stiffness / (z.effective_mass * omega_c**2):.2f}'
    # the regenerative chip: the mean feed force 0.5·u_s·d_a·f against the chip f
    out['chip_stiffness'] = f'{0.5 * plant["kline.specific_energy"] * depth:.1e}'.replace(
        'e+0', 'e'
    )
    return out
