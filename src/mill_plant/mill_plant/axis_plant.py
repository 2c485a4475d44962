"""The plant: three axes, each with its own dynamic model (mill_plant.models), coupled only
through the cutting force. Input per axis in its model's unit (N·m, or V).

Integration: fixed-step classical RK4 with `substeps` substeps per step; the cutting force
of all three axes is evaluated in every RK4 stage from the stage positions/velocities. The
input is held over the step (zero-order hold). A model with an input dead time T_d
(transfer-function axis) sees the held input delayed by T_d: that delayed signal is
piecewise constant and changes at known instants t_j + T_d; a substep containing such an
instant is split there (pieces of one substep integrated by one RK4 step each), so the dead
time is exact also when T_d is not a multiple of the step. Instants within 1e-9 substep of
a substep boundary are taken at the boundary. The input before the start was 0.

Coulomb friction (stick-slip), simple and chatter-free, on the coordinate FRICTION_DOF of
a model (mill_plant.models.base):

- At the start of every substep piece each axis gets a mode that is frozen for the piece,
  so RK4 always integrates a smooth right-hand side: sliding ±1 (friction -mu·mode) when
  the coordinate moves; at rest (velocity exactly 0.0) stuck if the net non-friction force
  is within ±mu (zero derivative: it stays exactly put), else sliding along that force.
- After the piece, a sliding coordinate whose velocity changed sign is stopped: velocity
  0.0 at the crossing x_old + v_old θ h / 2, θ = v_old / (v_old - v_new) (linear in v,
  exact for constant deceleration). Stiction is re-evaluated at the next piece, so the
  velocity reverses only once the net force exceeds breakaway the other way: no sign
  chatter at rest, for a dwell of at most one substep at a reversal.
- reversal 'through' (instead of the default 'stop'): the piece is integrated again up to
  the first crossing, that coordinate set to rest there, and the rest of the piece
  integrated from it with the modes evaluated anew, so a net force far above breakaway
  reverses the carriage at once. The dwell of 'stop' loses up to (net force)·h of momentum
  per reversal: nothing for the usual laws, but a switching law that reverses the carriage
  every sample (Chávez-Conde's sliding-mode GPI) is then dominated by it. 'through' takes
  the general path (no scalar path below).

Load change: at the first step whose start time is >= load_change_time, every axis gets
add_load(load_change_mass[i]) before the step is integrated (once; all axes or none: the
loaded models are copies that replace the old ones, see `models`).

Safety: a non-finite input on an axis never reaches the integrator; that axis is braked
for the step (all its velocities 0, positions held), reported as faulted and its applied
input is 0. Finite inputs are clipped to ±max_input (reported as saturated).

Three rigid axes (RigidAxisModel itself, the common case) take a scalar path: the same
RK4, friction and brake arithmetic in the same order, unrolled over the axes without the
state lists and per-stage model calls (about 3x faster; same bits, which a test pins).

The plant integrates deep copies of the given models; the caller's models never change.
Plain float arithmetic in a fixed order: same inputs, bit-identical outputs.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from dataclasses import dataclass

from mill_plant.cutting import CuttingForceModel, Force3
from mill_plant.models.base import AxisModel, State
from mill_plant.models.rigid import RigidAxisModel

Bool3 = tuple[bool, bool, bool]
Float3 = tuple[float, float, float]
_INF3 = (math.inf, math.inf, math.inf)
_SPLIT_TOL = 1e-9  # switch instants this close (in substeps) to a boundary snap to it
REVERSALS = ('stop', 'through')  # a coordinate whose velocity crosses zero (module docstring)
_MAX_REVERSALS = 8  # per piece, with 'through'; past that, the rest of the piece stops


@dataclass(frozen=True)
class StepReport:
    """What happened to the input command in one step.

    saturated: the input was clipped to +-max_input; faulted: the input was not finite
    and the axis was braked; applied_torque: the input the axis actually received, in its
    model's unit (N·m or V; 0.0 for a faulted axis).
    """

    saturated: Bool3
    faulted: Bool3
    applied_torque: Force3 = (0.0, 0.0, 0.0)


class AxisPlant:
    """Axes x, y, z with per-axis models, integrated by fixed-step RK4."""

    def __init__(
        self,
        models: Sequence[AxisModel],
        cutting: CuttingForceModel,
        initial_position: Sequence[float] = (0.0, 0.0, 0.0),
        max_input: Sequence[float] = _INF3,
        substeps: int = 4,
        start_time: float = 0.0,
        load_change_time: float = math.inf,
        load_change_mass: Sequence[float] = (0.0, 0.0, 0.0),
        reversal: str = 'stop',
    ) -> None:
        if reversal not in REVERSALS:
            raise ValueError(f'reversal must be one of {", ".join(REVERSALS)}, got {reversal!r}')
        if len(models) != 3:
            raise ValueError(f'models must have 3 entries (x, y, z), got {len(models)}')
        for i, model in enumerate(models):
            if not isinstance(model, AxisModel):
                raise ValueError(f'models[{i}] must be an AxisModel, got {type(model).__name__}')
            if not (math.isfinite(model.dead_time) and model.dead_time >= 0.0):
                raise ValueError(f'models[{i}].dead_time must be >= 0, got {model.dead_time!r}')
        if len(initial_position) != 3 or not all(math.isfinite(p) for p in initial_position):
            raise ValueError(f'initial_position must be 3 finite numbers, got {initial_position!r}')
        if len(max_input) != 3 or not all(
            (m == math.inf or math.isfinite(m)) and m > 0.0 for m in max_input
        ):
            raise ValueError(f'max_input must be 3 numbers > 0 (inf allowed), got {max_input!r}')
        if isinstance(substeps, bool) or not isinstance(substeps, int) or substeps < 1:
            raise ValueError(f'substeps must be a whole number >= 1, got {substeps!r}')
        if not math.isfinite(start_time):
            raise ValueError(f'start_time must be finite, got {start_time!r}')
        if math.isnan(load_change_time):
            raise ValueError('load_change_time must be a number (inf = never), got nan')
        if len(load_change_mass) != 3 or not all(math.isfinite(m) for m in load_change_mass):
            raise ValueError(f'load_change_mass must be 3 finite numbers, got {load_change_mass!r}')

        self._models: tuple[AxisModel, ...] = tuple(copy.deepcopy(m) for m in models)
        self._cutting = cutting
        self._max = tuple(float(m) for m in max_input)
        self._substeps = substeps
        self._t = float(start_time)
        self._load_time = float(load_change_time)
        self._load_mass = tuple(float(m) for m in load_change_mass)
        self._load_done = False
        self._through = reversal == 'through'
        self._theta = math.inf  # first crossing in the last _rk4 piece, as a fraction of it
        self._crossing = 0  # ... and the axis that crossed
        self._n = tuple(m.N_DOF for m in self._models)
        self._fdof = tuple(m.FRICTION_DOF for m in self._models)
        self._delay = tuple(float(m.dead_time) for m in self._models)
        self._bind()
        self._axpy_fn = tuple(_axpy_2 if n == 1 else _axpy for n in self._n)
        self._combine_fn = tuple(_combine_2 if n == 1 else _combine for n in self._n)
        # Per delayed axis: (instant the input reaches the plant, input), oldest first.
        self._history: list[list[tuple[float, float]]] = [
            [(-math.inf, 0.0)] if d > 0.0 else [] for d in self._delay
        ]
        self._state: list[State] = [
            m.initial_state(float(p)) for m, p in zip(self._models, initial_position, strict=True)
        ]
        # A path-dependent force model (mill_plant.cutting) learns every accepted state.
        self._commit = cutting.commit if cutting.PATH_DEPENDENT else None
        if self._commit is not None:
            self._commit(self._t, self.position, self.velocity)

    def _bind(self) -> None:
        """Cache the models' bound methods for the integration loop."""
        self._deriv_fn = tuple(m.derivative for m in self._models)
        self._pos_fn = tuple(m.position for m in self._models)
        self._vel_fn = tuple(m.velocity for m in self._models)
        rigid = [m for m in self._models if type(m) is RigidAxisModel]
        # Three rigid axes: the scalar path _step_rigid (module docstring).
        self._rigid = len(rigid) == 3 and not self._through
        self._terms_fn = tuple(m.scalar_terms for m in rigid)

    def _change_load(self) -> None:
        """Apply load_change_mass to all axes, all or nothing (ValueError names the mass)."""
        loaded = tuple(copy.deepcopy(m) for m in self._models)
        for model, mass in zip(loaded, self._load_mass, strict=True):
            if mass != 0.0:
                model.add_load(mass)
        self._models = loaded
        self._bind()
        self._load_done = True

    # ---- state -------------------------------------------------------------

    @property
    def time(self) -> float:
        """Current time [s]."""
        return self._t

    @property
    def position(self) -> Float3:
        """Carriage positions (x, y, z) [m]."""
        m, s = self._models, self._state
        return (m[0].position(s[0]), m[1].position(s[1]), m[2].position(s[2]))

    @property
    def velocity(self) -> Float3:
        """Carriage velocities [m/s]."""
        m, s = self._models, self._state
        return (m[0].velocity(s[0]), m[1].velocity(s[1]), m[2].velocity(s[2]))

    @property
    def states(self) -> tuple[tuple[float, ...], ...]:
        """Full model states (layout in mill_plant.models.base), a copy."""
        return tuple(tuple(s) for s in self._state)

    @property
    def models(self) -> tuple[AxisModel, ...]:
        return self._models

    @property
    def substeps(self) -> int:
        return self._substeps

    @property
    def load_changed(self) -> bool:
        """True once the scheduled load change has been applied."""
        return self._load_done

    @property
    def cutting(self) -> CuttingForceModel:
        """The cutting-force model the plant integrates with."""
        return self._cutting

    def cutting_force(self) -> Force3:
        """Cutting force (F_cx, F_cy, F_cz) [N] at the current time and state."""
        return self._cutting.force(self._t, self.position, self.velocity)

    # ---- input conditioning --------------------------------------------------

    def _condition(self, u: Sequence[float]) -> tuple[list[float], Bool3, Bool3]:
        """Clip to +-max_input; flag non-finite entries as faulted (input 0 there)."""
        if len(u) != 3:
            raise ValueError(f'input must have 3 entries (x, y, z), got {len(u)}')
        out = [0.0, 0.0, 0.0]
        sat = [False, False, False]
        fault = [False, False, False]
        for i in range(3):
            value = float(u[i])
            limit = self._max[i]
            if not math.isfinite(value):
                fault[i] = True
            elif value > limit:
                out[i] = limit
                sat[i] = True
            elif value < -limit:
                out[i] = -limit
                sat[i] = True
            else:
                out[i] = value
        return out, (sat[0], sat[1], sat[2]), (fault[0], fault[1], fault[2])

    def _delayed(self, i: int, t: float) -> float:
        """Input of delayed axis i acting at time t (right-continuous)."""
        value = 0.0
        for arrival, u in self._history[i]:
            if arrival > t:
                break
            value = u
        return value

    def _mode(self, i: int, y: State, u: float, f: float) -> float:
        """Frozen friction mode of axis i (mill_plant.models.base): +-1.0 sliding, 0.0 stuck."""
        j = self._fdof[i]
        if j is None:
            return 1.0
        v = y[self._n[i] + j]
        if v > 0.0:
            return 1.0
        if v < 0.0:
            return -1.0
        model = self._models[i]
        net = model.stick_force(y, u, f)
        mu = model.coulomb_friction
        if net > mu:
            return 1.0
        if net < -mu:
            return -1.0
        return 0.0

    def _rest_mode(self, i: int, x: float, u: float, f: float) -> float:
        """_mode of rigid axis i at rest at x."""
        return self._mode(i, [x, 0.0], u, f)

    # ---- dynamics ------------------------------------------------------------

    def step(self, u: Sequence[float], dt: float) -> StepReport:
        """Advance by dt [s] with the input u (each axis in its model's unit) held."""
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f'dt must be finite and > 0, got {dt!r}')
        if not self._load_done and self._t >= self._load_time:
            self._change_load()
        uc, saturated, faulted = self._condition(u)
        t0 = self._t
        states = self._state
        for i in range(3):
            if faulted[i]:  # braked: stopped now, derivative zero below
                n = self._n[i]
                states[i] = states[i][:n] + [0.0] * n
            if self._delay[i] > 0.0:
                self._history[i].append((t0 + self._delay[i], uc[i]))
        if self._rigid:
            self._state = self._step_rigid(uc, faulted, t0, dt)
            self._t = t0 + dt
            return StepReport(saturated, faulted, (uc[0], uc[1], uc[2]))
        n_sub = self._substeps
        h = dt / n_sub
        tol = _SPLIT_TOL * h
        switches = sorted(
            {s for hist in self._history for s, _ in hist if t0 + tol < s < t0 + dt - tol}
        )
        for k in range(n_sub):
            a = t0 + k * h
            cuts = [s for s in switches if a + tol < s < a + h - tol]
            if not cuts:
                states = self._piece(states, a, h, self._inputs(uc, a + 0.5 * h), faulted)
                self._accept(a + h, states)
                continue
            starts = [a]
            for s in cuts:
                if s - starts[-1] > tol:
                    starts.append(s)
            ends = [*starts[1:], a + h]
            for start, end in zip(starts, ends, strict=True):
                length = end - start
                states = self._piece(
                    states, start, length, self._inputs(uc, start + 0.5 * length), faulted
                )
                self._accept(end, states)
        self._state = states
        self._t = t0 + dt
        for hist in self._history:
            while len(hist) > 1 and hist[1][0] <= self._t:
                del hist[0]
        return StepReport(saturated, faulted, (uc[0], uc[1], uc[2]))

    def _accept(self, t: float, states: list[State]) -> None:
        """Tell a path-dependent force model the state accepted at time t."""
        if self._commit is None:
            return
        m = self._models
        self._commit(
            t,
            (m[0].position(states[0]), m[1].position(states[1]), m[2].position(states[2])),
            (m[0].velocity(states[0]), m[1].velocity(states[1]), m[2].velocity(states[2])),
        )

    def _inputs(self, uc: list[float], t_mid: float) -> list[float]:
        """Input acting on each axis over a piece whose midpoint is t_mid."""
        return [self._delayed(i, t_mid) if self._delay[i] > 0.0 else uc[i] for i in range(3)]

    def _piece(
        self, y: list[State], t: float, h: float, uu: list[float], faulted: Bool3
    ) -> list[State]:
        """One piece of a substep: _rk4, or with reversal 'through' up to each crossing and on
        from rest (module docstring)."""
        out = self._rk4(y, t, h, uu, faulted)
        if not self._through:
            return out
        for _ in range(_MAX_REVERSALS):
            if self._theta >= 1.0:
                return out
            first, i = self._theta * h, self._crossing
            out = self._rk4(y, t, first, uu, faulted)
            j = self._fdof[i]
            if j is not None:  # always: only a friction coordinate crosses
                out[i][self._n[i] + j] = 0.0  # at rest at its crossing (θ is linear)
            y, t, h = out, t + first, h - first
            out = self._rk4(y, t, h, uu, faulted)
        return out

    def _rk4(
        self, y1: list[State], t: float, h: float, uu: list[float], faulted: Bool3
    ) -> list[State]:
        """One classical RK4 step of length h from t with inputs uu; friction modes frozen.

        The three axes are written out (bound methods, plain lists): this is the hot loop.
        """
        force = self._cutting.force
        q0, q1, q2 = self._pos_fn
        w0, w1, w2 = self._vel_fn
        half = 0.5 * h
        sixth = h / 6.0
        ya, yb, yc = y1
        ua, ub, uc = uu

        f = force(t, (q0(ya), q1(yb), q2(yc)), (w0(ya), w1(yb), w2(yc)))
        sa, sb, sc = (0.0 if faulted[i] else self._mode(i, y1[i], uu[i], f[i]) for i in range(3))
        da, db, dc = (_zeros if faulted[i] else self._deriv_fn[i] for i in range(3))
        xa, xb, xc = self._axpy_fn
        ra, rb, rc = self._combine_fn
        # stage 1
        k1a, k1b, k1c = da(ya, ua, f[0], sa), db(yb, ub, f[1], sb), dc(yc, uc, f[2], sc)
        y2a = xa(ya, half, k1a)
        y2b = xb(yb, half, k1b)
        y2c = xc(yc, half, k1c)
        # stage 2
        f = force(t + half, (q0(y2a), q1(y2b), q2(y2c)), (w0(y2a), w1(y2b), w2(y2c)))
        k2a, k2b, k2c = da(y2a, ua, f[0], sa), db(y2b, ub, f[1], sb), dc(y2c, uc, f[2], sc)
        y3a = xa(ya, half, k2a)
        y3b = xb(yb, half, k2b)
        y3c = xc(yc, half, k2c)
        # stage 3
        f = force(t + half, (q0(y3a), q1(y3b), q2(y3c)), (w0(y3a), w1(y3b), w2(y3c)))
        k3a, k3b, k3c = da(y3a, ua, f[0], sa), db(y3b, ub, f[1], sb), dc(y3c, uc, f[2], sc)
        y4a = xa(ya, h, k3a)
        y4b = xb(yb, h, k3b)
        y4c = xc(yc, h, k3c)
        # stage 4
        f = force(t + h, (q0(y4a), q1(y4b), q2(y4c)), (w0(y4a), w1(y4b), w2(y4c)))
        k4a, k4b, k4c = da(y4a, ua, f[0], sa), db(y4b, ub, f[1], sb), dc(y4c, uc, f[2], sc)
        out = [
            ra(ya, sixth, k1a, k2a, k3a, k4a),
            rb(yb, sixth, k1b, k2b, k3b, k4b),
            rc(yc, sixth, k1c, k2c, k3c, k4c),
        ]
        # Stop a sliding coordinate whose velocity crossed zero (module docstring).
        self._theta = math.inf
        for i, mode in enumerate((sa, sb, sc)):
            j = self._fdof[i]
            if j is None or mode == 0.0:
                continue
            new = out[i]
            jv = self._n[i] + j
            if mode * new[jv] < 0.0:
                v = y1[i][jv]
                theta = v / (v - new[jv])
                if theta < self._theta:
                    self._theta, self._crossing = theta, i
                new[j], new[jv] = _stop_at_crossing(y1[i][j], v, new[jv], h)
        return out

    def _step_rigid(self, uc: list[float], faulted: Bool3, t0: float, dt: float) -> list[State]:
        """The substeps of step() for three rigid models, written out on scalars.

        The same arithmetic in the same order as _rk4 with _mode (so the same bits), without
        its lists and per-stage calls; the equation is the model's (drive_force and
        acceleration of RigidAxisModel, written out on its scalar_terms). Rigid models have
        no dead time: no pieces.
        """
        force = self._cutting.force
        commit = self._commit
        # drive_force and acceleration of RigidAxisModel, written out: the same expressions
        # (read every step: a caller may change a model's load in place).
        terms = [f() for f in self._terms_fn]
        (l0, w0, mu0, m0, e0), (l1, w1, mu1, m1, e1), (l2, w2, mu2, m2, e2) = terms
        mode = self._rest_mode
        (x0, v0), (x1, v1), (x2, v2) = self._state
        u0, u1, u2 = uc
        n = self._substeps
        h = dt / n
        half = 0.5 * h
        sixth = h / 6.0
        for k in range(n):
            t = t0 + k * h
            f1 = force(t, (x0, x1, x2), (v0, v1, v2))
            # Friction mode, frozen for the substep: _mode, asked only at rest (a braked axis
            # is at rest and held: mode 0).
            if v0:
                s0 = 1.0 if v0 > 0.0 else -1.0
            else:
                s0 = 0.0 if faulted[0] else mode(0, x0, u0, f1[0])
            if v1:
                s1 = 1.0 if v1 > 0.0 else -1.0
            else:
                s1 = 0.0 if faulted[1] else mode(1, x1, u1, f1[1])
            if v2:
                s2 = 1.0 if v2 > 0.0 else -1.0
            else:
                s2 = 0.0 if faulted[2] else mode(2, x2, u2, f1[2])
            # A stuck or braked axis has v = 0 and x'' = 0: it stays exactly put. Sliding:
            # g = drive_force(u, s), x'' = acceleration(v, g, F_c) = m * (g - F_c - e * v).
            g0 = u0 * l0 - w0 - mu0 * s0 if s0 else 0.0
            g1 = u1 * l1 - w1 - mu1 * s1 if s1 else 0.0
            g2 = u2 * l2 - w2 - mu2 * s2 if s2 else 0.0
            # stage 1
            a10 = m0 * (g0 - f1[0] - e0 * v0) if s0 else 0.0
            a11 = m1 * (g1 - f1[1] - e1 * v1) if s1 else 0.0
            a12 = m2 * (g2 - f1[2] - e2 * v2) if s2 else 0.0
            # stage 2
            p20 = v0 + half * a10
            p21 = v1 + half * a11
            p22 = v2 + half * a12
            f2 = force(t + half, (x0 + half * v0, x1 + half * v1, x2 + half * v2), (p20, p21, p22))
            a20 = m0 * (g0 - f2[0] - e0 * p20) if s0 else 0.0
            a21 = m1 * (g1 - f2[1] - e1 * p21) if s1 else 0.0
            a22 = m2 * (g2 - f2[2] - e2 * p22) if s2 else 0.0
            # stage 3
            p30 = v0 + half * a20
            p31 = v1 + half * a21
            p32 = v2 + half * a22
            f3 = force(
                t + half, (x0 + half * p20, x1 + half * p21, x2 + half * p22), (p30, p31, p32)
            )
            a30 = m0 * (g0 - f3[0] - e0 * p30) if s0 else 0.0
            a31 = m1 * (g1 - f3[1] - e1 * p31) if s1 else 0.0
            a32 = m2 * (g2 - f3[2] - e2 * p32) if s2 else 0.0
            # stage 4
            p40 = v0 + h * a30
            p41 = v1 + h * a31
            p42 = v2 + h * a32
            f4 = force(t + h, (x0 + h * p30, x1 + h * p31, x2 + h * p32), (p40, p41, p42))
            a40 = m0 * (g0 - f4[0] - e0 * p40) if s0 else 0.0
            a41 = m1 * (g1 - f4[1] - e1 * p41) if s1 else 0.0
            a42 = m2 * (g2 - f4[2] - e2 * p42) if s2 else 0.0
            # RK4 update
            nx0 = x0 + sixth * (v0 + 2.0 * p20 + 2.0 * p30 + p40)
            nx1 = x1 + sixth * (v1 + 2.0 * p21 + 2.0 * p31 + p41)
            nx2 = x2 + sixth * (v2 + 2.0 * p22 + 2.0 * p32 + p42)
            nv0 = v0 + sixth * (a10 + 2.0 * a20 + 2.0 * a30 + a40)
            nv1 = v1 + sixth * (a11 + 2.0 * a21 + 2.0 * a31 + a41)
            nv2 = v2 + sixth * (a12 + 2.0 * a22 + 2.0 * a32 + a42)
            # Stop an axis whose velocity crossed zero (module docstring).
            if s0 * nv0 < 0.0:
                nx0, nv0 = _stop_at_crossing(x0, v0, nv0, h)
            if s1 * nv1 < 0.0:
                nx1, nv1 = _stop_at_crossing(x1, v1, nv1, h)
            if s2 * nv2 < 0.0:
                nx2, nv2 = _stop_at_crossing(x2, v2, nv2, h)
            x0, x1, x2 = nx0, nx1, nx2
            v0, v1, v2 = nv0, nv1, nv2
            if commit is not None:
                commit(t + h, (x0, x1, x2), (v0, v1, v2))
        return [[x0, v0], [x1, v1], [x2, v2]]

    def disturbance(self, u: Sequence[float]) -> Float3:
        """Lumped disturbance xi_i = x_i'' - b_i u_i [m/s²] now, with this input applied.

        x_i'' is the actual carriage acceleration (with the input acting now: for a
        dead-time axis the delayed one), b_i = input_gain() and u_i the clipped input; each
        model computes it (AxisModel.disturbance). A stuck carriage has x'' = 0. An axis
        with a non-finite input (braked): NaN.
        """
        uc, _, faulted = self._condition(u)
        fc = self.cutting_force()
        out = [math.nan, math.nan, math.nan]
        for i in range(3):
            if faulted[i]:
                continue
            model = self._models[i]
            y = self._state[i]
            ui = self._delayed(i, self._t) if self._delay[i] > 0.0 else uc[i]
            mode = self._mode(i, y, ui, fc[i])
            out[i] = model.disturbance(y, ui, fc[i], mode, uc[i])
        return (out[0], out[1], out[2])


def _zeros(state: Sequence[float], u: float, force: float, mode: float) -> State:
    """Derivative of a braked axis."""
    return [0.0] * len(state)


def _stop_at_crossing(x: float, v: float, v_new: float, h: float) -> tuple[float, float]:
    """Position and velocity (0.0) where the velocity reached zero inside a piece of length h."""
    theta = v / (v - v_new)  # fraction of the piece at the crossing (linear in v)
    return x + 0.5 * v * theta * h, 0.0


# RK4 helpers on plain lists; the 2-state versions are written out (hot loop, ~4x faster).
def _axpy(y: State, c: float, k: State) -> State:
    """y + c k."""
    return [a + c * b for a, b in zip(y, k, strict=True)]


def _axpy_2(y: State, c: float, k: State) -> State:
    return [y[0] + c * k[0], y[1] + c * k[1]]


def _combine(y: State, sixth: float, a: State, b: State, c: State, d: State) -> State:
    """RK4 update y + h/6 (k1 + 2 k2 + 2 k3 + k4)."""
    return [
        yi + sixth * (ai + 2.0 * bi + 2.0 * ci + di)
        for yi, ai, bi, ci, di in zip(y, a, b, c, d, strict=True)
    ]


def _combine_2(y: State, sixth: float, a: State, b: State, c: State, d: State) -> State:
    return [
        y[0] + sixth * (a[0] + 2.0 * b[0] + 2.0 * c[0] + d[0]),
        y[1] + sixth * (a[1] + 2.0 * b[1] + 2.0 * c[1] + d[1]),
    ]
