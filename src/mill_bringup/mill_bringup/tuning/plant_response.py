"""The plant's response that `tune`'s margins are taken on: measured where it is known.

ROS-free. Per axis:

- the identified model as a continuous state space (rigid, or the motor-side two-mass model
  of mill_models.frequency_response), sampled exactly with the command held over a period
  and `delay` samples late: P(z) = c·(zI − Φ)⁻¹·Γ·z^(−d);
- the measured response X/U of the identify record (mill_models.frequency_response), used
  wherever its coherence is good inside the band it was fitted over, and the model
  elsewhere (below the band friction dominates, above it the excitation had no power).

Both are discrete responses from the command sample to the position sample, as the loop
sees the axis.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from mill_models.axis_model import TWO_MASS, AxisModel
from mill_models.identification import AxisIdentification
from scipy.linalg import expm

MIN_COHERENCE = 0.8  # a measured bin is used from this coherence up
# The identify job's small, dithered motion lets friction damp the resonance: issue 32's M2
# (screw ζ 0.03) measured ζ 0.039 and a peak 3 dB below the true one while the fit put the
# friction's damping on the whole axis (0.029 now that it is on the motor side). The
# margins are also required on the fitted model with its damping times this
# (`lightly_damped`).
DAMPING_SHARE = 0.5

Space = tuple[np.ndarray, np.ndarray, np.ndarray]  # (A, B, c) of x' = Ax + Bu, y = c·x


@dataclass(frozen=True)
class SampledPlant:
    """x[k+1] = Φ·x[k] + Γ·u[k − delay], y = c·x: the plant as the loop sees it."""

    phi: np.ndarray
    gamma: np.ndarray
    c: np.ndarray
    delay: int
    sample_period: float

    def response(self, w: np.ndarray) -> np.ndarray:
        """P(e^(jωT)) at ω [rad/s]."""
        z = np.exp(1j * np.asarray(w, float) * self.sample_period)
        n = len(self.gamma)
        out = np.empty(z.shape, complex)
        for i, zi in enumerate(z.flat):
            # P(z) = c·(zI − Φ)⁻¹·Γ·z^(−d)
            out.flat[i] = self.c @ np.linalg.solve(zi * np.eye(n) - self.phi, self.gamma)
        return out * z ** (-self.delay)


def sample(space: Space, T: float, delay: int) -> SampledPlant:
    """The zero-order-hold sampling of a continuous state space."""
    a, b, c = space
    n = len(b)
    m = np.zeros((n + 1, n + 1))
    m[:n, :n], m[:n, n] = a, b
    # Φ = e^(AT), Γ = ∫₀ᵀ e^(Aτ)dτ·B, both from one exponential (Van Loan 1978)
    e = expm(m * T)
    return SampledPlant(e[:n, :n], e[:n, n], np.asarray(c, float), delay, T)


def rigid_space(b: float, alpha: float) -> Space:
    """x'' = b·u − α·x' (the rigid fit's linear part; mill_models.identification)."""
    return np.array([[0.0, 1.0], [0.0, -alpha]]), np.array([0.0, b]), np.array([1.0, 0.0])


def two_mass_space(b: float, ratio: float, omega_r: float, zeta: float, alpha: float) -> Space:
    """The motor-side two-mass axis in shares of its whole mass M = 1/(a·b): motor side
    m1 = 1/(1 + r), table m2 = r/(1 + r), the screw's stiffness k and damping c between them,
    viscous friction α on the motor side; measured on the motor (state x1, v1, x2, v2)."""
    m1, m2 = 1.0 / (1.0 + ratio), ratio / (1.0 + ratio)
    mu = m1 * m2  # reduced mass μ = m1·m2/M, M = 1
    k = omega_r**2 * mu  # ωr² = k/μ
    c = 2.0 * zeta * omega_r * mu  # ζ = c/(2√(kμ))
    a = np.array(
        [
            [0.0, 1.0, 0.0, 0.0],
            # m1·x1'' = b·u − k(x1 − x2) − c(v1 − v2) − α·v1
            [-k / m1, -(c + alpha) / m1, k / m1, c / m1],
            [0.0, 0.0, 0.0, 1.0],
            # m2·x2'' = k(x1 − x2) + c(v1 − v2)
            [k / m2, c / m2, -k / m2, -c / m2],
        ]
    )
    return a, np.array([0.0, b / m1, 0.0, 0.0]), np.array([1.0, 0.0, 0.0, 0.0])


def model_space(
    structure: AxisModel | None, fit: AxisIdentification, damping: float = 1.0
) -> Space:
    """The identified model's linear part: two-mass when identify chose it (its damping
    ratio times `damping`), else rigid."""
    alpha = max(0.0, fit.alpha.value)
    tm = structure.two_mass if structure is not None and is_two_mass(structure) else None
    if tm is not None:
        zeta = damping * tm.zeta.value
        return two_mass_space(fit.b.value, tm.mass_ratio.value, tm.omega_r.value, zeta, alpha)
    return rigid_space(fit.b.value, alpha)


def is_two_mass(structure: AxisModel | None) -> bool:
    return structure is not None and structure.model == TWO_MASS and structure.two_mass is not None


def lightly_damped(
    structure: AxisModel | None, fit: AxisIdentification, T: float, delay: int
) -> PlantResponse | None:
    """A two-mass axis's fitted model with DAMPING_SHARE of its damping (None if rigid)."""
    if not is_two_mass(structure):
        return None
    empty = np.zeros(0)
    model = sample(model_space(structure, fit, DAMPING_SHARE), T, delay)
    return PlantResponse(model, empty, empty.astype(complex), empty.astype(bool))


@dataclass(frozen=True)
class PlantResponse:
    """The response the margins are taken on: measured bins where coherent, else the model."""

    model: SampledPlant
    f: np.ndarray  # measured bins [Hz] (empty: the model alone)
    h: np.ndarray  # measured X/U [m per N·m]
    usable: np.ndarray  # bins to use (coherent, inside the fitted band)

    def __call__(self, w: np.ndarray) -> np.ndarray:
        return self.split(w)[0]

    def split(self, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(P(ω), True where it is the measurement's)."""
        w = np.asarray(w, float)
        p = self.model.response(w)
        measured = np.zeros(w.shape, bool)
        if self.f.size < 2:
            return p, measured
        f = w / (2.0 * math.pi)
        i = np.clip(np.searchsorted(self.f, f) - 1, 0, self.f.size - 2)
        ok = (f >= self.f[i]) & (f <= self.f[i + 1]) & self.usable[i] & self.usable[i + 1]
        if ok.any():
            lo, hi = self.h[i[ok]], self.h[i[ok] + 1]
            t = (f[ok] - self.f[i[ok]]) / (self.f[i[ok] + 1] - self.f[i[ok]])
            # between two bins: log-magnitude and phase linear, h = h_i·(h_i+1/h_i)^t
            p[ok] = lo * np.exp(t * np.log(hi / lo))
            measured[ok] = True
        return p, measured


def plant_response(
    structure: AxisModel | None,
    fit: AxisIdentification,
    T: float,
    delay: int,
    min_coherence: float = MIN_COHERENCE,
) -> PlantResponse | None:
    """The axis's response at the rate and delay tuned for; None when nothing was measured
    and the model is the rigid one (the margins on the model are all there is). The
    measurement counts only at the rate it was taken at (its bins are the discrete response
    of that rate)."""
    model = sample(model_space(structure, fit), T, delay)
    frf = structure.response if structure is not None else None
    empty = np.zeros(0)
    r = frf.response if frf is not None else None
    same_rate = r is not None and math.isclose(r.sample_period, T, rel_tol=1e-9)
    if frf is None or r is None or r.f.size < 2 or not same_rate:
        if not is_two_mass(structure):
            return None
        return PlantResponse(model, empty, empty.astype(complex), empty.astype(bool))
    lo, hi = frf.band
    usable = (r.coherence >= min_coherence) & np.isfinite(r.h) & (np.abs(r.h) > 0)
    if math.isfinite(lo) and math.isfinite(hi):
        usable &= (r.f >= lo) & (r.f <= hi)
    # tuned for another delay than the one measured: the difference in whole samples
    more = delay - fit.delay
    h = r.h * np.exp(-2j * math.pi * r.f * T * more)
    return PlantResponse(model, r.f, h, usable)


ResponseFn = Callable[[np.ndarray], np.ndarray]
