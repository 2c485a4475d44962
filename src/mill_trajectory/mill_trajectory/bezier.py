"""Rest-to-rest Bézier move of Chávez-Conde section 5, per axis (ROS-free).

    F*(t) = F_o + (F_f − F_o) ψ(Δ),
    ψ(Δ) = Δ⁸ [r1 − r2 Δ + r3 Δ² − r4 Δ³ + r5 Δ⁴ − r6 Δ⁵ + r7 Δ⁶ − r8 Δ⁷ + r9 Δ⁸],

r = 12870, 91520, 288288, 524160, 600600, 443520, 205920, 54912, 6435.

Readings: the paper prints Δ = (T2 − T1)/(t − T1); the blend is Δ = (t − T1)/(T2 − T1),
clamped to [0, 1] (papers README). The paper moves x from 0 to 10 mm with T1 = 0, T2 = 3 s;
here each axis has its own start and end position, all sharing T1 and T2.

Velocity and acceleration are the exact derivatives: ψ is a degree-16 polynomial in Δ,
dF*/dt = (F_f − F_o) ψ'(Δ)/(T2 − T1), d²F*/dt² = (F_f − F_o) ψ''(Δ)/(T2 − T1)², and
zero outside [T1, T2]. With the printed r, ψ(0) = 0, ψ(1) = 1, derivatives 1…7 of ψ vanish
at Δ = 0 and 1…8 at Δ = 1 (ψ − 1 has the factor (1 − Δ)⁹), and ψ' > 0 on (0, 1): the move
is monotone and the reference is seven times continuously differentiable in t. It is not
symmetric: ψ(1/2) = 0.598, the peak speed is at Δ = 7/15 (ψ'max = 3.249: 10.8 mm/s for
the paper's 10 mm in 3 s).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from mill_common.declared import ParamSet, param
from mill_common.parameters import ParameterError, non_negative, number_list, positive

from mill_trajectory.base import Point, Trajectory, TrajectorySample, box

# Chávez-Conde section 5: r1 … r9.
BEZIER_R = (12870, 91520, 288288, 524160, 600600, 443520, 205920, 54912, 6435)
# ψ(Δ) = Σ c_j Δ^j, low → high: c_j = 0 for j < 8, c_{8+k} = (−1)^k r_{k+1}.
PSI = (0,) * 8 + tuple((-1) ** k * r for k, r in enumerate(BEZIER_R))
_D1 = 16 * math.comb(15, 7)  # 102960 = 8·r1

CHAVEZ_START = (0.0, 0.0, 0.0)
CHAVEZ_END = (0.01, 0.0, 0.0)
CHAVEZ_T1 = 0.0
CHAVEZ_T2 = 3.0


def blend(delta: float) -> tuple[float, float, float]:
    """(ψ, dψ/dΔ, d²ψ/dΔ²) at Δ, Δ clamped to [0, 1] (derivatives 0 outside).

    The printed polynomial equals the binomial tail ψ(Δ) = Σ_{j=8}^{16} C(16,j) Δ^j (1−Δ)^{16−j}
    (same coefficients; checked in the tests). Summing its positive terms (Δ ≤ 1/2), or
    1 − the complementary terms (Δ > 1/2), avoids the cancellation of the alternating
    monomial sum (coefficients up to 6·10⁵), which breaks monotonicity near Δ = 1 by
    ~1e-11. ψ' = 16·C(15,7) Δ⁷(1−Δ)⁸ and ψ'' = ψ'·(7 − 15Δ)/(Δ(1−Δ)) are products.
    """
    if delta <= 0.0:
        return 0.0, 0.0, 0.0
    if delta >= 1.0:
        return 1.0, 0.0, 0.0
    rest = 1.0 - delta
    if delta <= 0.5:
        psi = math.fsum(math.comb(16, j) * delta**j * rest ** (16 - j) for j in range(8, 17))
    else:
        psi = 1.0 - math.fsum(math.comb(16, j) * delta**j * rest ** (16 - j) for j in range(8))
    # d/dΔ of the binomial tail: 16·C(15,7) Δ⁷ (1−Δ)⁸ = 102960 Δ⁷ (1−Δ)⁸
    d1 = _D1 * delta**7 * rest**8
    d2 = _D1 * delta**6 * rest**7 * (7.0 - 15.0 * delta)
    return psi, d1, d2


@dataclass(frozen=True)
class BezierParams(ParamSet):
    """Chávez-Conde section 5: from F_o to F_f between T1 and T2."""

    PREFIX: ClassVar[str] = 'bezier'
    start: list[float] = param(
        list(CHAVEZ_START), 'start position F_o of x, y, z', number_list(3), unit='m'
    )
    end: list[float] = param(
        list(CHAVEZ_END), 'end position F_f of x, y, z', number_list(3), unit='m'
    )
    t1: float = param(CHAVEZ_T1, 'time T1 the move starts', non_negative, unit='s')
    t2: float = param(CHAVEZ_T2, 'time T2 the move ends [s] (> t1)', positive)

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.t2 > self.t1:
            raise ParameterError('bezier.t2', self.t2, f'must be > t1 = {self.t1!r}')


class BezierRestToRest(Trajectory):
    """All three axes move from `start` to `end` between t1 and t2, at rest at both ends."""

    PARAMS: ClassVar[type[BezierParams]] = BezierParams

    def __init__(self, params: BezierParams = BezierParams()) -> None:
        start, end = params.start, params.end
        self.start: tuple[float, float, float] = (start[0], start[1], start[2])
        self.end: tuple[float, float, float] = (end[0], end[1], end[2])
        self.t1 = params.t1
        self.t2 = params.t2
        self.end_time = self.t2
        self._span = tuple(f - o for o, f in zip(self.start, self.end, strict=True))

    def sample(self, t: float) -> TrajectorySample:
        duration = self.t2 - self.t1
        # Chávez-Conde section 5, misprint fixed: Δ = (t − T1)/(T2 − T1), clamped to [0, 1]
        psi, dpsi, ddpsi = blend((t - self.t1) / duration)
        # F*(t) = F_o + (F_f − F_o) ψ(Δ); chain rule dΔ/dt = 1/(T2 − T1)
        pos = tuple(o + s * psi for o, s in zip(self.start, self._span, strict=True))
        vel = tuple(s * dpsi / duration for s in self._span)
        acc = tuple(s * ddpsi / duration**2 for s in self._span)
        return TrajectorySample(pos, vel, acc)  # type: ignore[arg-type]

    def bounds(self, step: float) -> tuple[Point, Point]:
        # the blend rises monotonically from 0 to 1: the path stays between its ends
        return box([self.sample(self.t1).position, self.sample(self.t2).position])
