"""Loop margins of the Hatwesh 2013 x drive, sampled exactly: `python -m
mill_controllers.hatwesh_margins` prints the figures docs/papers.md quotes (ROS-free).

The drive of Table 1, J ω' = K_a K_t u − B ω (eq. (3)), x = r_g θ, with u held over T:
ω(k+1) = α ω(k) + β u(k), α = e^{−BT/J}, β = K_a K_t (1 − α)/B. The velocity the PI sees is
either sampled, v(k) = r_g ω(k), or the backward difference of the position,
v(k) = (x(k) − x(k−1))/T = (r_g/T)(c₁ ω(k−1) + c₂ u(k−1)), c₁ = (1 − α)J/B,
c₂ = K_a K_t (T − c₁)/B. The PI is C(z) = K_p + K_i T/(1 − z⁻¹) (as _VelocityPi runs it).
"""

from __future__ import annotations

import cmath
import math
from collections.abc import Callable

from mill_common.signals import FopdtEstimate

from mill_controllers.adaptive_pi import HATWESH_KI, HATWESH_KP, HATWESH_PITCH
from mill_controllers.phase_margin import DESIGN_RULES, design_pi

# Hatwesh 2013 Table 1, x axis.
KA, KT, B, J, T = 15.7311, 1.39, 14e-4, 2.8828e-3, 0.25e-3
VELOCITIES = ('sampled', 'difference')

Loop = Callable[[complex], complex]


def plant(velocity: str) -> Loop:
    """P(z) from u [V] to the measured velocity [m/s] of the nominal x drive."""
    rg = HATWESH_PITCH / (2 * math.pi)
    alpha = math.exp(-B * T / J)
    beta = KA * KT * (1 - alpha) / B
    c1 = (1 - alpha) * J / B
    c2 = KA * KT * (T - c1) / B
    if velocity == 'sampled':
        return lambda z: rg * beta / (z - alpha)
    return lambda z: rg / T * (c1 * beta / (z - alpha) + c2) / z


def pi(k_p: float, k_i: float) -> Loop:
    return lambda z: k_p + k_i * T / (1 - 1 / z)


def machine_pi() -> Loop:
    """Table 1's PI read in motor rev/s: 1/pitch rev/s per m/s of the table."""
    return pi(HATWESH_KP / HATWESH_PITCH, HATWESH_KI / HATWESH_PITCH)


def series(*parts: Loop) -> Loop:
    """The product of transfer functions, L(z) = Π parts(z)."""
    return lambda z: math.prod(p(z) for p in parts)


def margin(loop: Loop) -> tuple[float, float]:
    """(ω_c [rad/s], phase margin [deg]) at the first crossing of |L(e^{jωT})| through 1;
    (nan, nan) if |L| stays above 1 up to the Nyquist frequency (then the loop is unstable:
    the phase there is −π)."""

    def mag(x: float) -> float:
        return abs(loop(cmath.exp(1j * x))) - 1.0

    grid = [math.pi * (i + 1) / 4096 for i in range(4095)]
    hi = next((x for x in grid if mag(x) <= 0.0), math.nan)
    if math.isnan(hi):
        return math.nan, math.nan
    lo = hi - math.pi / 4096
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if mag(mid) > 0.0 else (lo, mid)
    x = 0.5 * (lo + hi)
    return x / T, 180.0 + math.degrees(cmath.phase(loop(cmath.exp(1j * x))))


def drive_model(velocity: str) -> FopdtEstimate:
    """The true FOPDT of the drive: K = K_a K_t r_g/B, τ = J/B, θ_d = T/2 for the difference."""
    d = 0.5 if velocity == 'difference' else 0.0
    return FopdtEstimate(KA * KT * HATWESH_PITCH / (2 * math.pi * B), J / B, d * T, d, 0)


def report() -> str:
    lines = ['Hatwesh 2013 x drive (Table 1), nominal, T = 0.25 ms, the loop sampled exactly:']
    for velocity in VELOCITIES:
        w, pm = margin(series(machine_pi(), plant(velocity)))
        lines.append(
            f'machine PI, {velocity} velocity: crossover {w:.0f} rad/s, phase margin {pm:.1f}°'
        )
    lines.append('phase-margin rules on the true model (K, τ, θ_d), and the margin they give:')
    for velocity in VELOCITIES:
        model = drive_model(velocity)
        for phi in (25.0, 60.0):
            for rule in DESIGN_RULES:
                kp, ki, w_gc = design_pi(rule, model, math.radians(phi), T)
                w, pm = margin(series(pi(kp, ki), plant(velocity)))
                got = f'crossover {w:.0f} rad/s, phase margin {pm:.1f}°'
                if math.isnan(w):
                    got = '|L| > 1 up to the Nyquist frequency: unstable'
                lines.append(
                    f'{velocity:<10} φ_m {phi:2.0f}° {rule:<10} ω_gc {w_gc:4.0f} rad/s, '
                    f'K_p {kp:6.2f} V/(m/s), K_i {ki:6.2f} V/m → {got}'
                )
    return '\n'.join(lines)


if __name__ == '__main__':
    print(report())
