"""The stability margins of one axis's loop as built, on its identified model and on its
measured frequency response.

The loop is the observer and control loop the nodes run (built from the tuned parameters),
closed around the exactly sampled model x'' = b·u − α·x' with the identified delay. Broken
at the plant input: an impulse d is added to the command, and with u_p = u_c + d the return
ratio is L = −U_c / U_p (the closed loop is stable, so both sequences die out and their
transforms are well defined). The same run with the impulse on the measurement gives how
much the encoder's quantization moves the command (its noise gain).

On the measured response: the loop's controller (law, observer and delay compensation, as
one discrete transfer function from the measured position to the command) is
C = L / P₀, P₀ the sampled rigid model the run was closed around; the return ratio on the
axis as it is, L = C·P, takes P from mill_bringup.tuning.plant_response (the identify
record's response where coherent, the fitted model elsewhere). Its margins are every gain
crossover's distance from −1 (the smallest counts: a resonance's peak crosses 1 again) and
the smallest gain margin where the phase crosses −180° with |L| < 1. That the loop is
stable on the axis is checked apart, by closing it around the fitted model (two-mass or
rigid) in the same impulse run.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from mill_common.reference_buffer import ReferenceBuffer
from mill_common.signals import AxisReference
from mill_controllers.control_loop import AxisControlLoop
from mill_observers.observer_loop import ObserverLoop

from mill_bringup.tuning.plant_response import (
    PlantResponse,
    SampledPlant,
    rigid_space,
    sample,
)

SAMPLES = 1 << 13  # 8 s at 1 kHz: the loop settles within one; ω resolution 0.8 rad/s
SIZE = 1e-9  # impulse size: small, so that no limit is reached [N·m, m]
DIVERGED = 1e-2  # a command this large after so small an impulse: the loop diverges [N·m]


class UnstableLoop(ValueError):
    """The loop does not settle on the identified model."""


@dataclass(frozen=True)
class Margins:
    crossover: float  # gain crossover ω_gc [rad/s]
    phase: float  # phase margin [deg]
    gain_db: float  # gain margin [dB] (inf: the phase never reaches −180°)
    delay: float  # delay margin: phase margin / ω_gc [samples]
    noise_gain: float  # RMS command per RMS measurement noise [N·m per m]
    measured: Margins | None = None  # on the measured response (None: none was given)
    stable: bool = True  # the loop settles on the fitted model (measured margins only)
    share: float = 0.0  # of the response's bins below Nyquist that are measured ones
    # the return ratio the margins were read from: ω [rad/s] and L(e^(jωT))
    curve: tuple[np.ndarray, np.ndarray] | None = field(default=None, compare=False, repr=False)

    def text(self) -> str:
        gm = 'inf' if math.isinf(self.gain_db) else f'{self.gain_db:.1f} dB'
        return (
            f'crossover {self.crossover:.0f} rad/s, phase margin {self.phase:.0f}°, '
            f'gain margin {gm}, delay margin {self.delay:.2f} samples'
        )

    def reach(self, floor_db: float) -> float:
        """The highest ω where the loop gain is still floor_db or more [rad/s] (nan: no
        curve)."""
        if self.curve is None:
            return math.nan
        w, L = self.curve
        above = np.flatnonzero(np.abs(L) >= 10.0 ** (floor_db / 20.0))
        return float(w[above[-1]]) if above.size else 0.0

    def holds(self, min_phase: float, min_gain_db: float) -> bool:
        return self.stable and self.phase >= min_phase and self.gain_db >= min_gain_db


def sampled_plant(b: float, alpha: float, T: float) -> tuple[np.ndarray, np.ndarray]:
    """Φ, Γ of x'' = b·u − α·x' with u held over T (state [x, x'])."""
    p = sample(rigid_space(b, alpha), T, 0)
    return p.phi, p.gamma


def _respond(
    observer: ObserverLoop,
    loop: AxisControlLoop,
    plant: SampledPlant,
    at_input: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """(u_c, u_p) after an impulse at the plant input (or on the measurement)."""
    phi, gamma, c, T = plant.phi, plant.gamma, plant.c, plant.sample_period
    x = np.zeros(len(gamma))
    queue: deque[float] = deque([0.0] * plant.delay)
    refs = ReferenceBuffer()
    dt_ns = round(T * 1e9)
    zero = AxisReference(0.0, 0.0, 0.0)
    uc, up = np.zeros(SAMPLES), np.zeros(SAMPLES)
    acted: float | None = None
    for k in range(SAMPLES):
        ns = k * dt_ns
        refs.add(loop.aim(ns), zero)
        if k == 0:
            refs.add(0, zero)
        y = float(c @ x) + (SIZE if (k == 0 and not at_input) else 0.0)
        est = observer.step(y, acted)
        u = loop.step(ns, y, est, refs, None).effort
        if not math.isfinite(u) or abs(u) > DIVERGED:
            raise UnstableLoop('the loop does not settle on the identified model')
        acted = u
        refs.forget_before(ns)
        applied = u + (SIZE if (k == 0 and at_input) else 0.0)
        uc[k], up[k] = u, applied
        queue.append(applied)
        x = phi @ x + gamma * queue.popleft()
    tail = np.abs(up[-SAMPLES // 8 :]).max()
    if tail > 1e-6 * np.abs(up).max():
        raise UnstableLoop('the loop does not settle on the identified model')
    return uc, up


def margins(
    rebuild: Callable[[], tuple[ObserverLoop, AxisControlLoop]],
    b: float,
    alpha: float,
    delay: int,
    T: float,
    response: PlantResponse | None = None,
    worst_case: PlantResponse | None = None,
) -> Margins:
    """Margins of the loop `rebuild()` builds (a fresh observer and loop per run) on the
    rigid model, and with `response` on the axis's response too (`.measured`; with
    `worst_case` the smaller of the margins on both)."""
    rigid = sample(rigid_space(b, alpha), T, delay)
    observer, loop = rebuild()
    uc, up = _respond(observer, loop, rigid, at_input=True)
    # without ω = 0: the loop's integrators make L infinite there (and U_p zero)
    L = -np.fft.rfft(uc)[1:] / np.fft.rfft(up)[1:]
    w = np.fft.rfftfreq(SAMPLES, T)[1:] * 2.0 * math.pi
    observer, loop = rebuild()
    un, _ = _respond(observer, loop, rigid, at_input=False)
    noise_gain = float(np.sqrt(np.sum((un / SIZE) ** 2)))
    found = loop_margins(w, L, T, noise_gain)
    if response is None:
        return found
    # the controller as one transfer function from position to command: C = L/P₀
    C = L / rigid.response(w)
    found_on = [_on(rebuild, w, C, r, noise_gain) for r in (response, worst_case) if r]
    # the worse: unstable first, then the smaller gain margin
    on_axis = min(found_on, key=lambda m: (m.stable, min(m.gain_db, m.phase / 5.0)))
    return replace(found, measured=on_axis)


def _on(
    rebuild: Callable[[], tuple[ObserverLoop, AxisControlLoop]],
    w: np.ndarray,
    C: np.ndarray,
    response: PlantResponse,
    noise_gain: float,
) -> Margins:
    p, measured = response.split(w)
    on_axis = loop_margins(w, C * p, response.model.sample_period, noise_gain, strict=False)
    stable = on_axis.stable
    if stable:
        observer, loop = rebuild()
        try:
            _respond(observer, loop, response.model, at_input=True)
        except UnstableLoop:
            stable = False
    return replace(on_axis, stable=stable, share=float(measured.mean()))


def loop_margins(
    w: np.ndarray, L: np.ndarray, T: float, noise_gain: float = math.nan, strict: bool = True
) -> Margins:
    """Margins of the return ratio L(e^(jωT)) on the grid ω (module doc). strict: a loop
    that never crosses 1 is an error (else it gets infinite margins and stable = False)."""
    mag = np.abs(L)
    lm = np.log(mag)
    phase = np.degrees(np.unwrap(np.angle(L)))
    crossings = np.flatnonzero((mag[:-1] >= 1.0) != (mag[1:] >= 1.0))
    if not crossings.size:
        if strict:
            raise UnstableLoop('the loop gain never falls below 1')
        return Margins(math.nan, math.inf, math.inf, math.inf, noise_gain, stable=False)
    # each crossing between two bins, log|L| taken linear in between
    t = -lm[crossings] / (lm[crossings + 1] - lm[crossings])
    wx = w[crossings] + t * (w[crossings + 1] - w[crossings])
    px = phase[crossings] + t * (phase[crossings + 1] - phase[crossings])
    # at each crossover: 180° + ∠L, ∠L taken in (−360°, 0]; its size is the distance of L
    # from −1 there (the loop's low-frequency phase is −180°: a double integrator)
    pms = px % 360.0 - 180.0
    worst = int(np.argmin(np.abs(pms)))
    pm = float(pms[worst])
    delays = np.radians(np.abs(pms)) / (wx * T)
    # −180° crossings (the phase passes an odd multiple of 180°) where |L| < 1
    odd = np.floor((phase + 180.0) / 360.0)
    gains = []
    for j in np.flatnonzero(np.diff(odd) != 0.0):
        target = 360.0 * max(odd[j], odd[j + 1]) - 180.0
        f = (target - phase[j]) / (phase[j + 1] - phase[j])
        g = math.exp(lm[j] + f * (lm[j + 1] - lm[j]))
        if g < 1.0:
            gains.append(g)
    gm = -20.0 * math.log10(max(gains)) if gains else math.inf
    return Margins(float(wx[worst]), pm, gm, float(delays.min()), noise_gain, curve=(w, L))
