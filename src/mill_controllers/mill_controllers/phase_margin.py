"""The phase-margin PI design of Hatwesh 2013 ("PI controller design"), two rules (ROS-free).

Both design K(s) = K_i (1 + τ s)/s (eq. (8), a = K_i, b = τ: the PI zero cancels the plant
pole) for the FOPDT estimate K e^{−θ_d s}/(τ s + 1) (eq. (10)) so that ∠L = −π + φ_m where
|L| = 1.

'continuous': the hold read as a delay T/2, L(s) = K_i K e^{−θs}/s with θ = θ_d + T/2,
    ω_gc = (π/2 − φ_m)/θ,  K_i = ω_gc/K,  K_p = τ K_i.
'discrete' (exact for the sampled loop): the PI as it runs, u = K_p e + I, I += K_i T e, i.e.
    C(z) = K_p + K_i T/(1 − z⁻¹), on the discrete model of eq. (11) with the estimate's
    fractional delay d = n + f samples split over two taps,
    P(z) = Σb·z^{−n−1}(1 − f + f z⁻¹)/(1 − a z⁻¹),  a = e^{−T/τ},  Σb = K (1 − a).
    The zero of C at z = a cancels the pole: K_i T = K_p (1 − a)/a, and then
    L(z) = (K_p/a)·G(z),  G(z) = Σb·z^{−n−1}(1 − f + f z⁻¹)/(1 − z⁻¹),
    ∠G(e^{jx}) = −π/2 − (n + ½) x − atan2(f sin x, 1 − f + f cos x),   x = ω T,
    ω_gc T = the first x with ∠G = −π + φ_m (bisection),  K_p = a/|G(e^{jω_gc T})|.
    For the rls model of a backward-difference velocity (b_1 ≈ b_2, d = ½) both rules give
    ω_gc = (π/2 − φ_m)/T; the discrete K_p is 2 tan(x/2)/x times the continuous one (×1.12 at
    25°, ×1.02 at 60°), since the continuous rule drops the hold's magnitude.
"""

from __future__ import annotations

import cmath
import math

from mill_common.signals import FopdtEstimate

__all__ = ['DESIGN_RULES', 'design_pi', 'phase_margin_pi', 'phase_margin_pi_discrete']

DESIGN_RULES = ('continuous', 'discrete')


def _check(model: FopdtEstimate, phase_margin: float, theta: float) -> None:
    if not (0.0 < phase_margin < 0.5 * math.pi):
        raise ValueError(f'phase margin must be in (0, π/2) rad, got {phase_margin!r}')
    if not (theta > 0.0 and model.gain > 0.0 and 0.0 < model.time_constant < math.inf):
        raise ValueError(f'no phase-margin design for {model!r} (θ = {theta!r})')


def phase_margin_pi(
    model: FopdtEstimate, phase_margin: float, hold_delay: float
) -> tuple[float, float, float]:
    """(K_p, K_i, ω_gc) of the continuous rule, θ = θ_d + hold_delay (see the module).

    phase_margin in rad, in (0, π/2). K_p [u per y-unit], K_i [u per y-unit·s], ω_gc [rad/s].
    """
    theta = model.dead_time + hold_delay
    _check(model, phase_margin, theta)
    # Hatwesh 2013: ∠L(jω_gc) = −π + φ_m with L = K_i K e^{−θs}/s ⇒ ω_gc = (π/2 − φ_m)/θ
    w_gc = (0.5 * math.pi - phase_margin) / theta
    # Hatwesh 2013: |L(jω_gc)| = 1 ⇒ K_i = ω_gc/K; eq. (8) b = τ ⇒ K_p = K_i τ
    k_i = w_gc / model.gain
    return k_i * model.time_constant, k_i, w_gc


def _lag(x: float, n: int, f: float) -> float:
    """−(∠G(e^{jx}) + π/2): the phase lag of G beyond the integrator's −π/2."""
    return (n + 0.5) * x + math.atan2(f * math.sin(x), 1.0 - f + f * math.cos(x))


def phase_margin_pi_discrete(
    model: FopdtEstimate, phase_margin: float, sample_period: float
) -> tuple[float, float, float]:
    """(K_p, K_i, ω_gc) of the exact discrete rule for the PI u = K_p e + I, I += K_i T e."""
    T = sample_period
    _check(model, phase_margin, T)
    d = max(0.0, model.dead_time_samples)
    n, f = int(d), d - int(d)
    a = math.exp(-T / model.time_constant)
    b_sum = model.gain * (1.0 - a)
    target = 0.5 * math.pi - phase_margin
    # The first crossing of the lag through π/2 − φ_m: a coarse scan, then bisection.
    grid = [math.pi * (i + 1) / 64 for i in range(64)]
    hi = next(x for x in grid if _lag(x, n, f) >= target)
    lo = hi - math.pi / 64
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _lag(mid, n, f) < target else (lo, mid)
    x = 0.5 * (lo + hi)
    zi = cmath.exp(-1j * x)  # z⁻¹ on the unit circle
    g = b_sum * zi ** (n + 1) * (1.0 - f + f * zi) / (1.0 - zi)
    # Hatwesh 2013 "PI controller design": |L| = 1 where ∠L = −π + φ_m, on L(z) = (K_p/a) G(z)
    k_p = a / abs(g)
    return k_p, k_p * (1.0 - a) / (a * T), x / T


def design_pi(
    rule: str, model: FopdtEstimate, phase_margin: float, sample_period: float
) -> tuple[float, float, float]:
    """(K_p, K_i, ω_gc) by the named rule ('continuous': θ = θ_d + T/2; 'discrete': exact)."""
    if rule == 'continuous':
        return phase_margin_pi(model, phase_margin, 0.5 * sample_period)
    if rule == 'discrete':
        return phase_margin_pi_discrete(model, phase_margin, sample_period)
    raise ValueError(f'design rule must be one of {DESIGN_RULES}, got {rule!r}')
