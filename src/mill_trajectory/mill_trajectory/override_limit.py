"""How fast a feed override may change on a planned path, and the override that follows. ROS-free.

Under an override o(t) the reference of path p(τ), dτ/dt = o, is, per axis:

    v = o p',   a = o² p'' + ȯ p',   j = o³ p''' + 3 o ȯ p'' + ö p'

The planner keeps |p'| ≤ V_p, |p''| ≤ A_p, |p'''| ≤ J_p (mill_trajectory.planner) with the
machine's limits V, A, J shared out for an override up to o_max: V_p = V/o_max,
A_p = (1 − ρ) A/o_max², J_p = (1 − ρ) J/o_max³, the reserve ρ (RESERVE) left for the
override's changes. An override whose rate |ȯ| ≤ R and whose change of rate |ö| ≤ D, with

    R = min over axes of ρA/V_p and (ρJ/2)/(3 o_max A_p),   D = min of (ρJ − 3 o_max R A_p)/V_p

then keeps |a| ≤ A and |j| ≤ J on every axis, at any instant: the planned terms take at
most (1 − ρ) of each limit, the override's the rest.

`OverrideLimit.of` gives None where no limit binds (no acceleration nor jerk limit).
`FollowedOverride` is the override of such a path: it follows the offered one (the Rubio
controller's, once per revolution; a user's on /mill/feed_override) as fast as R and D
allow, ö constant over each sample, and never passes the offered value on its way: the
point where it would come to rest braking at D, sample by sample, stays on the near side of
the target, and it comes to rest on it. So it stays within the override's range as well.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

RESERVE = 0.25  # ρ: the share of the acceleration and jerk limits left for override changes


@dataclass(frozen=True)
class OverrideLimit:
    """Largest |ȯ| [1/s] and |ö| [1/s²] of the override on a planned path."""

    rate: float
    change: float

    @classmethod
    def of(
        cls,
        velocity: tuple[float, ...],
        acceleration: tuple[float, ...],
        jerk: tuple[float, ...],
        override_max: float,
        reserve: float = RESERVE,
    ) -> OverrideLimit | None:
        """From the machine's per-axis limits (inf: none) and the override's maximum."""
        rate = change = math.inf
        o = override_max
        v_p = [v / o for v in velocity]
        a_p = [(1.0 - reserve) * a / o**2 for a in acceleration]
        for vp, a, ap, j in zip(v_p, acceleration, a_p, jerk, strict=True):
            rate = min(rate, reserve * a / vp)
            if math.isfinite(j) and math.isfinite(ap):
                rate = min(rate, 0.5 * reserve * j / (3.0 * o * ap))
        for vp, ap, j in zip(v_p, a_p, jerk, strict=True):
            if math.isfinite(j):
                cross = 3.0 * o * rate * ap if math.isfinite(ap) else 0.0
                change = min(change, (reserve * j - cross) / vp)
        return None if math.isinf(rate) and math.isinf(change) else cls(rate, change)


class FollowedOverride:
    """The override o and its rate w = ȯ, following an offered one within a limit."""

    def __init__(self, limit: OverrideLimit, initial: float = 1.0) -> None:
        self.limit = limit
        self.value = float(initial)
        self.rate = 0.0

    def step(self, target: float, T: float) -> float:
        """Over one sample of T toward target; returns the path time it covers."""
        o, w = self.value, self.rate
        R, D = self.limit.rate, self.limit.change
        if math.isinf(D):  # no jerk limit: the rate may reach R within a sample
            D = R / T
        # The rate x = u·DT at the sample's end from which braking by DT a sample (the last
        # step less) comes to rest exactly at the target. From u = m + f (m whole) it covers
        # DT²(u² + f − f²)/2, so (w + x)T/2 + that = target − o reads, with
        # Y = 2(target − o − wT/2)/(DT²): u² + u + f − f² = Y, linear in u for each m.
        step = D * T
        Y = 2.0 * (target - o - 0.5 * w * T) / (step * T)
        m = math.floor(0.5 * (math.sqrt(1.0 + 4.0 * abs(Y)) - 1.0))
        x = math.copysign(step * (abs(Y) + m + m * m) / (2.0 * (m + 1)), Y)
        x = min(max(x, -R, w - D * T), R, w + D * T)
        self.value, self.rate = o + 0.5 * (w + x) * T, x
        # ö = (x − w)/T over the sample: τ gains o T + w T²/2 + ö T³/6.
        return o * T + 0.5 * w * T * T + (x - w) * T * T / 6.0
