"""The stability margins of one axis's loop as built, on its identified linear model.

The loop is the observer and control loop the nodes run (built from the tuned parameters),
closed around the exactly sampled model x'' = b·u − α·x' with the identified delay. Broken
at the plant input: an impulse d is added to the command, and with u_p = u_c + d the return
ratio is L = −U_c / U_p (the closed loop is stable, so both sequences die out and their
transforms are well defined). The same run with the impulse on the measurement gives how
much the encoder's quantization moves the command (its noise gain).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from mill_common.reference_buffer import ReferenceBuffer
from mill_common.signals import AxisReference
from mill_controllers.control_loop import AxisControlLoop
from mill_observers.observer_loop import ObserverLoop
from scipy.linalg import expm

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

    def text(self) -> str:
        gm = 'inf' if math.isinf(self.gain_db) else f'{self.gain_db:.1f} dB'
        return (
            f'crossover {self.crossover:.0f} rad/s, phase margin {self.phase:.0f}°, '
            f'gain margin {gm}, delay margin {self.delay:.2f} samples'
        )


def sampled_plant(b: float, alpha: float, T: float) -> tuple[np.ndarray, np.ndarray]:
    """Φ, Γ of x'' = b·u − α·x' with u held over T (state [x, x'])."""
    m = np.zeros((3, 3))
    m[0, 1], m[1, 1], m[1, 2] = 1.0, -alpha, b
    e = expm(m * T)
    return e[:2, :2], e[:2, 2]


def _respond(
    observer: ObserverLoop,
    loop: AxisControlLoop,
    b: float,
    alpha: float,
    delay: int,
    T: float,
    at_input: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """(u_c, u_p) after an impulse at the plant input (or on the measurement)."""
    phi, gamma = sampled_plant(b, alpha, T)
    x = np.zeros(2)
    queue: deque[float] = deque([0.0] * delay)
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
        y = x[0] + (SIZE if (k == 0 and not at_input) else 0.0)
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
) -> Margins:
    """Margins of the loop `rebuild()` builds (a fresh observer and loop per run)."""
    observer, loop = rebuild()
    uc, up = _respond(observer, loop, b, alpha, delay, T, at_input=True)
    # without ω = 0: the loop's integrators make L infinite there (and U_p zero)
    L = -np.fft.rfft(uc)[1:] / np.fft.rfft(up)[1:]
    w = np.fft.rfftfreq(SAMPLES, T)[1:] * 2.0 * math.pi
    mag = np.abs(L)
    phase = np.unwrap(np.angle(L))
    # the phase wraps from the loop's low-frequency −180° (double integrator) downwards
    crossings = np.flatnonzero((mag[:-1] >= 1.0) & (mag[1:] < 1.0))
    if not crossings.size:
        raise UnstableLoop('the loop gain never falls below 1')
    i = int(crossings[-1])
    pm = math.degrees(phase[i]) % 360.0 - 180.0  # 180° + ∠L, ∠L taken in (−360°, 0°]
    wrapped = (np.degrees(phase) + 180.0) % 360.0 - 180.0  # −180..180
    phase_x = np.flatnonzero((np.abs(np.diff(wrapped)) > 180.0) & (np.arange(len(w) - 1) > i))
    gm = -20.0 * math.log10(mag[phase_x[0]]) if phase_x.size else math.inf
    observer, loop = rebuild()
    un, _ = _respond(observer, loop, b, alpha, delay, T, at_input=False)
    noise_gain = float(np.sqrt(np.sum((un / SIZE) ** 2)))
    return Margins(float(w[i]), pm, gm, math.radians(pm) / (w[i] * T), noise_gain)
