"""Three rigid ball-screw axes coupled only through the cutting force, Beltrán 2013 eq. (1)-(3).

Per axis (Beltrán 2013 eq. (3)):

    x' = v
    v' = (tau/a - F_c - c_e v - mu sign(v)) / m_e

The cutting force F_c(t, x, v) of all three axes comes from one
CuttingForceModel and is evaluated inside every Runge-Kutta stage.

Integration: the torque is held over a step (zero-order hold) and the step is
split into `substeps` classical RK4 substeps of fixed length. Everything is
plain float arithmetic in a fixed order, so the same inputs give bit-identical
outputs (a distributed run is compared with an offline run).

Coulomb friction (stick-slip), chosen to be simple and chatter-free:

- At the start of every substep each axis gets a mode that is frozen for the
  substep, so RK4 always integrates a smooth right-hand side:
  * moving (v != 0): sliding, friction -mu sign(v);
  * at rest (v == 0.0 exactly): the net non-friction force tau/a - F_c is
    compared with mu. If |net| <= mu the axis is stuck: its derivative is zero
    in all stages, so v stays exactly 0.0 and x is unchanged. Otherwise it
    breaks away and slides in the direction of net, friction -mu sign(net).
- After the substep, a sliding axis whose velocity has changed sign
  (crossed zero) is stopped: v = 0.0 and x is the position at the crossing,
  x_old + v_old theta h / 2 with theta = v_old / (v_old - v_new) the crossing
  located by linear interpolation of v (exact for constant deceleration).
  Stiction is re-evaluated at the next substep, so the velocity can only
  reverse after the net force has exceeded the breakaway force in the other
  direction: no sign chatter at rest. The cost is a dwell of at most one
  substep (dt/substeps) at a reversal.

Safety: a non-finite torque on an axis never reaches the integrator; that
axis is braked for the whole step (v = 0, x held) and reported as faulted.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from mill_models.axis_data import RigidAxisParams

from mill_plant.axis_plant import Bool3, StepReport
from mill_plant.cutting import CuttingForceModel, Force3

_INF3 = (math.inf, math.inf, math.inf)


class ThreeAxisPlant:
    """The x, y, z axes of Beltrán 2013 eq. (1)-(3), integrated by fixed-step RK4."""

    def __init__(
        self,
        axes: Sequence[RigidAxisParams],
        cutting: CuttingForceModel,
        initial_position: Sequence[float] = (0.0, 0.0, 0.0),
        max_torque: Sequence[float] = _INF3,
        substeps: int = 4,
        start_time: float = 0.0,
    ) -> None:
        if len(axes) != 3:
            raise ValueError(f'axes must have 3 entries (x, y, z), got {len(axes)}')
        for i, axis in enumerate(axes):
            if not isinstance(axis, RigidAxisParams):
                raise ValueError(f'axes[{i}] must be RigidAxisParams, got {type(axis).__name__}')
            axis.validate()
        if len(initial_position) != 3 or not all(math.isfinite(p) for p in initial_position):
            raise ValueError(f'initial_position must be 3 finite numbers, got {initial_position!r}')
        if len(max_torque) != 3 or not all(
            (m == math.inf or math.isfinite(m)) and m > 0.0 for m in max_torque
        ):
            raise ValueError(f'max_torque must be 3 numbers > 0 (inf allowed), got {max_torque!r}')
        if isinstance(substeps, bool) or not isinstance(substeps, int) or substeps < 1:
            raise ValueError(f'substeps must be a whole number >= 1, got {substeps!r}')
        if not math.isfinite(start_time):
            raise ValueError(f'start_time must be finite, got {start_time!r}')

        self._axes = tuple(axes)
        self._cutting = cutting
        self._max_torque = tuple(float(m) for m in max_torque)
        self._substeps = substeps
        self._inv_lead = tuple(1.0 / a.lead for a in axes)
        self._inv_me = tuple(1.0 / a.effective_mass for a in axes)
        self._ce = tuple(a.effective_damping for a in axes)
        self._mu = tuple(a.coulomb_friction for a in axes)
        self._gain = tuple(a.input_gain for a in axes)
        self._t = float(start_time)
        self._x = [float(p) for p in initial_position]
        self._v = [0.0, 0.0, 0.0]
        # A path-dependent force model (mill_plant.cutting) learns every accepted state.
        self._commit = cutting.commit if cutting.PATH_DEPENDENT else None
        if self._commit is not None:
            self._commit(self._t, self.position, self.velocity)

    # ---- state -------------------------------------------------------------

    @property
    def time(self) -> float:
        """Current time [s]."""
        return self._t

    @property
    def position(self) -> tuple[float, float, float]:
        """Axis positions (x, y, z) [m]."""
        x = self._x
        return (x[0], x[1], x[2])

    @property
    def velocity(self) -> tuple[float, float, float]:
        """Axis velocities [m/s]."""
        v = self._v
        return (v[0], v[1], v[2])

    @property
    def axes(self) -> tuple[RigidAxisParams, ...]:
        return self._axes

    @property
    def substeps(self) -> int:
        return self._substeps

    def cutting_force(self) -> Force3:
        """Cutting force (F_cx, F_cy, F_cz) [N] at the current time and state."""
        return self._cutting.force(self._t, self.position, self.velocity)

    # ---- torque conditioning -------------------------------------------------

    def _condition(self, torque: Sequence[float]) -> tuple[list[float], Bool3, Bool3]:
        """Clip to +-max_torque; flag non-finite entries as faulted (torque 0 there)."""
        if len(torque) != 3:
            raise ValueError(f'torque must have 3 entries (x, y, z), got {len(torque)}')
        tau = [0.0, 0.0, 0.0]
        sat = [False, False, False]
        fault = [False, False, False]
        for i in range(3):
            value = float(torque[i])
            limit = self._max_torque[i]
            if not math.isfinite(value):
                fault[i] = True
            elif value > limit:
                tau[i] = limit
                sat[i] = True
            elif value < -limit:
                tau[i] = -limit
                sat[i] = True
            else:
                tau[i] = value
        return tau, (sat[0], sat[1], sat[2]), (fault[0], fault[1], fault[2])

    # ---- dynamics ------------------------------------------------------------

    def step(self, torque: Sequence[float], dt: float) -> StepReport:
        """Advance by dt [s] with the torque [N·m] held constant; returns what was applied."""
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f'dt must be finite and > 0, got {dt!r}')
        tau, saturated, faulted = self._condition(torque)
        force = self._cutting.force
        inv_me = self._inv_me
        ce0, ce1, ce2 = self._ce
        mu = self._mu
        # tau/a: the translational drive force of eq. (1)
        ta = [tau[i] * self._inv_lead[i] for i in range(3)]
        x0, x1, x2 = self._x
        v0, v1, v2 = self._v
        # A faulted axis is braked: stopped now, and kept stopped below (w = 0).
        if faulted[0]:
            v0 = 0.0
        if faulted[1]:
            v1 = 0.0
        if faulted[2]:
            v2 = 0.0
        n = self._substeps
        h = dt / n
        half = 0.5 * h
        sixth = h / 6.0
        t_start = self._t
        w = [0.0, 0.0, 0.0]  # 1/m_e when the axis moves in this substep, 0.0 when held
        g = [0.0, 0.0, 0.0]  # tau/a - mu*s for the frozen sliding direction s
        s = [0.0, 0.0, 0.0]
        for k in range(n):
            t = t_start + k * h
            f1 = force(t, (x0, x1, x2), (v0, v1, v2))
            # Mode of each axis for this substep (module docstring: stick-slip).
            for i, vi in enumerate((v0, v1, v2)):
                if faulted[i]:
                    w[i] = 0.0
                    s[i] = 0.0
                    continue
                if vi > 0.0:
                    si = 1.0
                elif vi < 0.0:
                    si = -1.0
                else:
                    net = ta[i] - f1[i]
                    if net > mu[i]:
                        si = 1.0
                    elif net < -mu[i]:
                        si = -1.0
                    else:
                        w[i] = 0.0  # stuck: static friction balances the net force
                        s[i] = 0.0
                        continue
                w[i] = inv_me[i]
                s[i] = si
                g[i] = ta[i] - mu[i] * si
            w0, w1, w2 = w
            g0, g1, g2 = g
            # Beltrán 2013 eq. (3): v' = (tau/a - F_c - c_e v - mu sign(v)) / m_e
            a10 = w0 * (g0 - f1[0] - ce0 * v0)
            a11 = w1 * (g1 - f1[1] - ce1 * v1)
            a12 = w2 * (g2 - f1[2] - ce2 * v2)
            # stage 2
            p20 = v0 + half * a10
            p21 = v1 + half * a11
            p22 = v2 + half * a12
            f2 = force(t + half, (x0 + half * v0, x1 + half * v1, x2 + half * v2), (p20, p21, p22))
            a20 = w0 * (g0 - f2[0] - ce0 * p20)
            a21 = w1 * (g1 - f2[1] - ce1 * p21)
            a22 = w2 * (g2 - f2[2] - ce2 * p22)
            # stage 3
            p30 = v0 + half * a20
            p31 = v1 + half * a21
            p32 = v2 + half * a22
            f3 = force(
                t + half, (x0 + half * p20, x1 + half * p21, x2 + half * p22), (p30, p31, p32)
            )
            a30 = w0 * (g0 - f3[0] - ce0 * p30)
            a31 = w1 * (g1 - f3[1] - ce1 * p31)
            a32 = w2 * (g2 - f3[2] - ce2 * p32)
            # stage 4
            p40 = v0 + h * a30
            p41 = v1 + h * a31
            p42 = v2 + h * a32
            f4 = force(t + h, (x0 + h * p30, x1 + h * p31, x2 + h * p32), (p40, p41, p42))
            a40 = w0 * (g0 - f4[0] - ce0 * p40)
            a41 = w1 * (g1 - f4[1] - ce1 * p41)
            a42 = w2 * (g2 - f4[2] - ce2 * p42)
            # RK4 update; a held axis has v = 0 and all a = 0, so it stays exactly put.
            nx0 = x0 + sixth * (v0 + 2.0 * p20 + 2.0 * p30 + p40)
            nx1 = x1 + sixth * (v1 + 2.0 * p21 + 2.0 * p31 + p41)
            nx2 = x2 + sixth * (v2 + 2.0 * p22 + 2.0 * p32 + p42)
            nv0 = v0 + sixth * (a10 + 2.0 * a20 + 2.0 * a30 + a40)
            nv1 = v1 + sixth * (a11 + 2.0 * a21 + 2.0 * a31 + a41)
            nv2 = v2 + sixth * (a12 + 2.0 * a22 + 2.0 * a32 + a42)
            # Stop an axis whose velocity crossed zero (module docstring).
            s0, s1, s2 = s
            if s0 * nv0 < 0.0:
                nx0, nv0 = _stop_at_crossing(x0, v0, nv0, h)
            if s1 * nv1 < 0.0:
                nx1, nv1 = _stop_at_crossing(x1, v1, nv1, h)
            if s2 * nv2 < 0.0:
                nx2, nv2 = _stop_at_crossing(x2, v2, nv2, h)
            x0, x1, x2 = nx0, nx1, nx2
            v0, v1, v2 = nv0, nv1, nv2
            if self._commit is not None:
                self._commit(t + h, (x0, x1, x2), (v0, v1, v2))
        self._x = [x0, x1, x2]
        self._v = [v0, v1, v2]
        self._t = t_start + dt
        return StepReport(saturated, faulted, (tau[0], tau[1], tau[2]))

    def disturbance(self, torque: Sequence[float]) -> tuple[float, float, float]:
        """True lumped disturbance xi_i = x_i'' - b_i tau_i [m/s²] now, with this torque applied.

        Uses the clipped torque. Stuck axis: x'' = 0, so xi = -b tau. An axis
        with a non-finite torque (braked) has no defined xi: NaN.
        """
        tau, _, faulted = self._condition(torque)
        fc = self.cutting_force()
        out = [0.0, 0.0, 0.0]
        for i in range(3):
            if faulted[i]:
                out[i] = math.nan
                continue
            v = self._v[i]
            mu = self._mu[i]
            if v > 0.0:
                sign = 1.0
            elif v < 0.0:
                sign = -1.0
            else:
                net = tau[i] * self._inv_lead[i] - fc[i]
                if abs(net) <= mu:
                    out[i] = -self._gain[i] * tau[i]
                    continue
                sign = 1.0 if net > 0.0 else -1.0
            # Beltrán 2013 eqs. (6)-(8): xi = -(c_e v + mu sign(v) + F_c) / m_e
            out[i] = -(self._ce[i] * v + mu * sign + fc[i]) * self._inv_me[i]
        return (out[0], out[1], out[2])


def _stop_at_crossing(x: float, v: float, v_new: float, h: float) -> tuple[float, float]:
    """Position where the velocity reached zero inside a substep, and v = 0."""
    theta = v / (v - v_new)  # fraction of the substep at the crossing (linear in v)
    return x + 0.5 * v * theta * h, 0.0
