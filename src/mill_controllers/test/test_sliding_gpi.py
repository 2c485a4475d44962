"""Sliding-mode GPI of Chávez-Conde eq. (13)-(17): linear part, switching, GPI comparison.

Measured on the Chávez-Conde x axis (Bézier 0 → 10 mm in 3 s, 1 ms, 0 … 3.5 s) with
Coulomb friction 0.3 N plus a constant 100 N force opposing +x (a stand-in for the mean
cutting force):
- GPI (ζ = 0.9, ω_n = p = 80): max |e| = 23.1 µm, rms 23.0 µm (steady (k2 − κ)ξ/(η1 k0)).
- sliding GPI, paper μ = 15, γ = 10, exact sign, 5 N·m torque limit (suite default):
  max |e| = 12.7 µm, rms 8.0 µm (σ̂ ≈ 0 leaves e = ξ/(η1 ω_n²) = 7.9 µm), but the torque
  chatters between the ±5 N·m limits.
- the same without a torque limit (the paper's law literally): ±546…621 N·m chattering and
  max |e| = 617 µm, rms 130 µm: worse than GPI. Not tuned; reported.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from mill_common.parameters import ParameterError
from mill_common.signals import AxisReference, ControlInputs, Estimate
from mill_controllers.gpi_controller import GpiController, GpiParams
from mill_controllers.sliding_gpi import SlidingGpiController, SlidingGpiParams

sys.path.insert(0, str(Path(__file__).parent))
from test_gpi_controller import (
    EST,
    ETA1,
    KAPPA,
    MU,
    B,
    T,
    _match,
    closed_loop_poles,
    simulate,
)

FORCE = 100.0


def test_linear_part_has_the_roots_of_eq15_times_s_plus_mu() -> None:
    ctrl = SlidingGpiController(
        B, T, SlidingGpiParams(gamma=0.0, damping_rate=KAPPA, torque_limit=math.inf)
    )
    got = closed_loop_poles(ctrl)
    wd = 80.0 * math.sqrt(1.0 - 0.81)
    _match(got, [complex(-72.0, wd), complex(-72.0, -wd), complex(-15.0)], atol=1e-4)
    assert ctrl.surface_gains == (6400.0, pytest.approx(144.0))


def test_continuous_gains_are_eq17_expanded() -> None:
    ctrl = SlidingGpiController(B, T, SlidingGpiParams(discretisation='continuous'))
    # (s² + 144 s + 6400)(s + 15): μα0, α0 + μα1, α1 + μ
    assert ctrl.gains == pytest.approx((96000.0, 8560.0, 159.0), rel=1e-12)
    with pytest.raises(ParameterError, match=r'sliding_gpi\.discretisation'):
        SlidingGpiController(B, T, SlidingGpiParams(discretisation='tustin'))


def test_switching_function() -> None:
    sign = SlidingGpiController(B, T)
    assert [sign.switch(s) for s in (-2.0, 0.0, 1e-12)] == [-1.0, 0.0, 1.0]
    sat = SlidingGpiController(B, T, SlidingGpiParams(boundary_layer=0.1))
    assert [sat.switch(s) for s in (-2.0, 0.05, 0.3)] == [-1.0, pytest.approx(0.5), 1.0]


def test_sigma_is_eq13() -> None:
    ctrl = SlidingGpiController(B, T, SlidingGpiParams(torque_limit=math.inf))
    ref = AxisReference(0.002, 0.001, 0.0)
    tau0 = ctrl.compute(ControlInputs(0.0, 0.0, ref, EST))
    tau = ctrl.compute(ControlInputs(T, 0.0005, ref, EST))
    int_e = T * (0.0 - 0.002)  # forward rectangle: e at t = 0
    f_hat = B * T * tau0  # eq. (10) with κ = 0
    assert ctrl.velocity_estimate == pytest.approx(f_hat)
    want = (f_hat - 0.001) + 144.0 * (0.0005 - 0.002) + 6400.0 * int_e
    assert ctrl.sigma == pytest.approx(want)
    assert math.isfinite(tau)


def _errors(ctrl) -> tuple[float, float, float]:
    e, tau = simulate(ctrl, force=FORCE, coulomb=MU)
    return float(np.max(np.abs(e))), float(np.sqrt(np.mean(e**2))), float(np.max(np.abs(tau)))


def test_sliding_reduces_the_gpi_error_with_the_torque_limit() -> None:
    gpi_max, gpi_rms, _ = _errors(GpiController(B, T, GpiParams(damping_rate=KAPPA)))
    smc_max, smc_rms, smc_tau = _errors(
        SlidingGpiController(B, T, SlidingGpiParams(damping_rate=KAPPA))
    )
    assert gpi_max == pytest.approx(23.1e-6, rel=0.05)
    assert smc_max < 0.6 * gpi_max
    assert smc_rms < 0.4 * gpi_rms
    # σ̂ ≈ 0 leaves ë + α1 ė + α0 e = ξ/η1: e = ξ/(η1 ω_n²).
    assert smc_rms == pytest.approx((FORCE + MU) / ETA1 / 6400.0, rel=0.1)
    assert smc_tau == pytest.approx(5.0)  # the switching term saturates the actuator


def test_literal_paper_gains_chatter_without_a_torque_limit() -> None:
    gpi_max, _, _ = _errors(
        GpiController(B, T, GpiParams(damping_rate=KAPPA, torque_limit=math.inf))
    )
    smc_max, _, smc_tau = _errors(
        SlidingGpiController(B, T, SlidingGpiParams(damping_rate=KAPPA, torque_limit=math.inf))
    )
    # μγ = 150 m/s² switched every sample: hundreds of N·m and a larger error than GPI.
    assert smc_tau > 400.0
    assert smc_max > 10.0 * gpi_max


def test_parameters() -> None:
    ctrl = SlidingGpiController.from_parameters(B, T, {'mu': 20, 'gamma': 0.5})
    assert ctrl.design_roots[2] == -20.0
    with pytest.raises(ParameterError, match=r'sliding_gpi\.gamma'):
        SlidingGpiController.from_parameters(B, T, {'gamma': -1.0})
    with pytest.raises(ParameterError, match=r'sliding_gpi\.boundary_layer'):
        SlidingGpiController(B, T, SlidingGpiParams(boundary_layer=math.nan))
    assert (
        SlidingGpiController(B, T).compute(
            ControlInputs(0.0, 0.0, AxisReference(0, 0, 0), Estimate(0, 0, 0))
        )
        == 0.0
    )
