"""The frequency response of an axis from its record, its resonances and a two-mass model.

ROS-free. From positions x[k] and commands u[k] (held over a period) sampled every T:

- The response X/U is estimated with Welch's averaged cross-spectra (scipy.signal.csd). In
  the identify job the command is a soft hold plus a random binary torque r: the hold feeds
  the friction and the encoder back into u, so the usual H1 = S_ux/S_uu is biased where the
  hold acts. When the binary torque is known (given, or read off the command's jumps:
  `excitation_from_command`) the estimate uses it as the instrument,
  H = S_rx/S_ru (the indirect, "joint input-output" estimate; Pintelon & Schoukens 2012,
  System Identification, §2.6), which the feedback does not bias; the coherence is that of
  r and x. Without it, H1 from u and the coherence of u and x.
- The acceleration response normalised by the sampled double integrator with a held input,
  N = H / (T²(z+1) / (2(z−1)²)), is flat at the input gain b for a rigid axis (times the
  delay's e^(−jωdT)); a compliant axis shows its dips and peaks on it.
- The two models fitted to N where the coherence is good (weighted by the coherence, on
  the logarithm of N, so gain and phase count alike):
    rigid:     N = b·e^(−sτ)·s/(s + α_e)
    two-mass:  N = b·e^(−sτ)·s²·X1/F of a motor side m1 driven by the torque and a table
               m2 on the screw's stiffness k and damping c, with the friction's damping
               α_e on the motor side (`_two_mass`), measured on the motor (collocated)
  α_e is the friction seen as damping (large below a few Hz, where Coulomb friction takes
  much of the torque; larger the smaller the motion). In the two-mass model it acts on the
  motor side, where the screw's bearings and nut are: put on the whole axis (the rigid line
  times the undamped two-mass ratio, as first written) it biased b by -2 to -4 % on issue
  32's M2 y. ωa² = k/m2, ωr² = k/μ (μ = m1·m2/M), so ωr/ωa = √(1 + m2/m1), and b is the
  whole axis's gain 1/(a·M).
- The band measured: `measured_to`, the highest frequency whose octave below is mostly
  coherent; `tune` keeps its loop gain's reach within it (mill_bringup.tuning.design).
- The two-mass model is chosen when it describes the data much better than the rigid one
  and its resonance is a real one: a peak above the rigid line, narrow, inside the band the
  data cover.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize, signal

from mill_models.identification import Z95, Interval


@dataclass(frozen=True)
class FrfSettings:
    segment: float = 2.048  # Welch segment [s]: resolution 1/segment
    min_coherence: float = 0.7  # bins used for the fit
    low: float = 10.0  # below this [Hz] friction dominates the response: not fitted
    high: float = 0.4  # × the sample rate: above, the sampled model drifts from the continuous
    min_bins: int = 20  # coherent bins needed for a fit
    improvement: float = 4.0  # the two-mass fit's χ² must be this many times below the rigid's
    min_peak: float = 1.5  # its peak above the rigid line [×]
    max_zeta: float = 0.25  # a resonance is narrow
    max_freq_error: float = 0.05  # the 95 % interval of its frequency within ± this
    band_drop: float = 20.0  # the excitation covers where its PSD is within this [dB]
    measured_share: float = 0.65  # of the bins in the octave below f coherent: measured to f


@dataclass(frozen=True)
class FrequencyResponse:
    """The response of one axis, per frequency bin."""

    f: np.ndarray  # [Hz]
    h: np.ndarray  # X/U [m per N·m]
    coherence: np.ndarray  # of the instrument (excitation or command) and x
    excitation_psd: np.ndarray  # of the instrument [(N·m)²/Hz]
    sample_period: float  # [s]
    segments: int  # averaged
    source: str  # 'excitation' (indirect estimate) or 'command' (H1)

    @property
    def acceleration(self) -> np.ndarray:
        """N = H / (sampled double integrator): b·e^(−jωdT) for a rigid axis."""
        T = self.sample_period
        z = np.exp(2j * math.pi * self.f * T)
        with np.errstate(divide='ignore', invalid='ignore'):
            # the double integrator sampled with a held input (zero-order hold): T²(z+1)/(2(z−1)²)
            return self.h * (2.0 * (z - 1.0) ** 2) / (T * T * (z + 1.0))

    def excitation_band(self, drop_db: float = 20.0) -> tuple[float, float]:
        """From the lowest bin up to where the excitation's PSD first falls drop_db below
        its level at low frequency (the median of the first tenth of the bins) [Hz]."""
        p = self.excitation_psd[1:]
        f = self.f[1:]
        level = float(np.median(p[: max(3, len(p) // 10)]))
        below = np.flatnonzero(p < level * 10.0 ** (-drop_db / 10.0))
        return float(f[0]), float(f[below[0] - 1] if below.size and below[0] > 0 else f[-1])


def measured_to(resp: FrequencyResponse, settings: FrfSettings | None = None) -> float | None:
    """The frequency up to which the response was measured coherently [Hz]: the highest f
    whose octave below, [f/2, f], has at least `measured_share` of its bins at
    `min_coherence` or more (a dip at an anti-resonance, where a motor-side axis barely
    moves, does not end the band; the end of the excitation's power or the encoder's
    noise does). None when no octave above `low` is measured so."""
    s = settings or FrfSettings()
    f, good = resp.f, resp.coherence >= s.min_coherence
    if f.size < 4:
        return None
    counts = np.concatenate([[0], np.cumsum(good)])
    top = None
    for i in np.flatnonzero(f >= 2.0 * s.low):
        j = int(np.searchsorted(f, 0.5 * f[i]))
        if (counts[i + 1] - counts[j]) >= s.measured_share * (i + 1 - j):
            top = float(f[i])
    return top


ISOLATED = 10  # [samples] between two flips for the later one to give the torque's size


def excitation_from_command(u: np.ndarray) -> np.ndarray | None:
    """The binary torque of the identify job read off the command: its flips are jumps of
    ±2·amplitude between two samples, far larger than what the soft hold changes in one
    (mill_controllers/excitation.py). None when the command has no such jumps."""
    du = np.diff(np.asarray(u, float))
    size = np.abs(du)
    if du.size < 100:
        return None
    big = float(np.quantile(size, 0.995))
    jumps = size > 0.5 * big
    if not big > 0.0 or not 0.002 < jumps.mean() < 0.3:
        return None
    # a flip soon after another carries the hold's answer to that one (the short bits): the
    # size from flips well apart from the one before, when there are enough of them
    at = np.flatnonzero(jumps)
    apart = at[1:][np.diff(at) >= ISOLATED]
    two_a = float(np.median(size[apart] if apart.size >= 20 else size[jumps]))
    # a binary torque: every jump the same size, and nothing else near that size
    if np.any(np.abs(size[jumps] - two_a) > 0.5 * two_a) or np.any(size[~jumps] > 0.35 * two_a):
        return None
    steps = np.where(jumps, np.sign(du) * two_a, 0.0)
    r = np.concatenate([[0.0], np.cumsum(steps)])
    return r - 0.5 * (r.max() + r.min())


def frequency_response(
    x: np.ndarray,
    u: np.ndarray,
    T: float,
    excitation: np.ndarray | None = None,
    settings: FrfSettings | None = None,
) -> FrequencyResponse:
    """The response X/U of the record, with the excitation as instrument when there is one
    (given, else read off the command's jumps)."""
    s = settings or FrfSettings()
    x, u = np.asarray(x, float), np.asarray(u, float)
    r = excitation if excitation is not None else excitation_from_command(u)
    n = len(x)
    nper = min(n // 4, max(16, round(s.segment / T)))
    fs = 1.0 / T
    x0, u0 = x - x.mean(), u - u.mean()
    if r is None:
        f, p_uu = signal.welch(u0, fs, nperseg=nper)
        _, p_ux = signal.csd(u0, x0, fs, nperseg=nper)
        _, coh = signal.coherence(u0, x0, fs, nperseg=nper)
        h, psd, source = p_ux / np.where(p_uu > 0, p_uu, np.inf), p_uu, 'command'
    else:
        r0 = np.asarray(r, float) - float(np.mean(r))
        f, p_ru = signal.csd(r0, u0, fs, nperseg=nper)
        _, p_rx = signal.csd(r0, x0, fs, nperseg=nper)
        _, psd = signal.welch(r0, fs, nperseg=nper)
        _, coh = signal.coherence(r0, x0, fs, nperseg=nper)
        # indirect estimate: X/U = S_rx / S_ru (Pintelon & Schoukens 2012 §2.6)
        h, source = p_rx / np.where(np.abs(p_ru) > 0, p_ru, np.inf), 'excitation'
    segments = max(1, 2 * n // nper - 1)  # Hann windows, half overlapping
    return FrequencyResponse(f, h, coh, psd, T, segments, source)


@dataclass(frozen=True)
class TwoMassModel:
    """Motor-side two-mass axis: b the whole axis's gain [m/s² per N·m], mass_ratio m2/m1,
    the resonance ωr [rad/s] with damping ratio ζ, the delay [s], and α_e the friction's
    equivalent damping [1/s] at low frequency."""

    b: Interval
    mass_ratio: Interval
    omega_r: Interval
    zeta: Interval
    delay: float
    friction_damping: float
    chi2: float  # per degree of freedom, of the fit

    @property
    def resonance_hz(self) -> float:
        return self.omega_r.value / (2.0 * math.pi)

    @property
    def anti_resonance_hz(self) -> float:
        # motor-side two-mass: ωa = ωr / √(1 + m2/m1)
        return self.resonance_hz / math.sqrt(1.0 + self.mass_ratio.value)

    @property
    def peak(self) -> float:
        """The response at the resonance over the rigid line's [×]."""
        w = np.array([self.omega_r.value])
        return float(
            abs(self.acceleration(w / (2.0 * math.pi))[0] / _rigid(self._params()[:3], w)[0])
        )

    def _params(self) -> np.ndarray:
        return np.concatenate(
            [
                [math.log(self.b.value), self.delay, math.log(self.friction_damping)],
                np.log([self.mass_ratio.value, self.omega_r.value, self.zeta.value]),
            ]
        )

    def acceleration(self, f: np.ndarray) -> np.ndarray:
        """N(f) of the model (as FrequencyResponse.acceleration) [m/s² per N·m]."""
        return _two_mass(self._params(), 2.0 * math.pi * np.asarray(f, float))

    def masses(self, lead: float) -> tuple[float, float, float]:
        """(m1, m2 [kg], k [N/m]) for a screw of lead a [m/rad]."""
        M = 1.0 / (lead * self.b.value)
        r = self.mass_ratio.value
        m1, m2 = M / (1.0 + r), M * r / (1.0 + r)
        # ωr² = k/μ, μ = m1·m2/M
        return m1, m2, self.omega_r.value**2 * m1 * m2 / M

    def as_dict(self) -> dict[str, float]:
        out: dict[str, float] = {}
        for name in ('b', 'mass_ratio', 'omega_r', 'zeta'):
            iv: Interval = getattr(self, name)
            out[name], out[f'{name}_ci'] = iv.value, iv.half_width
        out.update(
            resonance_hz=self.resonance_hz,
            anti_resonance_hz=self.anti_resonance_hz,
            delay=self.delay,
            friction_damping=self.friction_damping,
        )
        return out


@dataclass(frozen=True)
class FrfAnalysis:
    """What the response shows: the band fitted, the rigid line, the two-mass model if a
    resonance shows, and the choice between them with its reason."""

    response: FrequencyResponse
    band: tuple[float, float]  # fitted [Hz] (coherent bins within it)
    bins: int  # fitted
    b: float  # rigid line's gain
    delay: float  # rigid line's delay [s]
    rigid_chi2: float  # per degree of freedom
    two_mass: TwoMassModel | None  # chosen, or None
    candidate: TwoMassModel | None = None  # the best two-mass fit, chosen or not
    reason: str = ''
    excitation_band: tuple[float, float] = field(default=(0.0, 0.0))

    @property
    def resonant(self) -> bool:
        return self.two_mass is not None


def _rigid(p: np.ndarray, w: np.ndarray) -> np.ndarray:
    s = 1j * w
    return np.exp(p[0]) * np.exp(-s * p[1]) * s / (s + np.exp(p[2]))


def _two_mass(p: np.ndarray, w: np.ndarray) -> np.ndarray:
    """N of the motor-side two-mass axis (module doc) in shares of its whole mass M = 1:
    motor side m1 = 1/(1 + r), table m2 = r/(1 + r), the screw's k = ωr²·μ and c = 2ζωr·μ
    (μ = m1·m2) between them, and the friction's damping α_e on the motor side, where the
    screw's bearings and nut are (as mill_bringup.tuning.plant_response models it). Far below
    the resonance it is the rigid line b·e^(−sτ)·s/(s + α_e)."""
    s = 1j * w
    b, tau, alpha = np.exp(p[0]), p[1], np.exp(p[2])
    ratio, wr, zeta = np.exp(p[3]), np.exp(p[4]), np.exp(p[5])
    m1, m2 = 1.0 / (1.0 + ratio), ratio / (1.0 + ratio)
    mu = m1 * m2
    k, c = wr * wr * mu, 2.0 * zeta * wr * mu
    table = m2 * s * s + c * s + k
    # (m1·s² + (c + α)s + k)·X1 − (cs + k)·X2 = F, (cs + k)·X1 = table·X2; the constant
    # terms cancel: the denominator over s
    den = m1 * m2 * s**3 + (m1 * c + m2 * (c + alpha)) * s * s + (k + alpha * c) * s + alpha * k
    return b * np.exp(-s * tau) * s * table / den


def _residual(n: np.ndarray, model: np.ndarray, weight: np.ndarray) -> np.ndarray:
    q = n / model
    return np.concatenate([weight * np.log(np.abs(q)), weight * np.angle(q)])


def analyse(resp: FrequencyResponse, settings: FrfSettings | None = None) -> FrfAnalysis:
    """Fit the rigid and two-mass models to the coherent band and choose (module doc)."""
    s = settings or FrfSettings()
    T = resp.sample_period
    f, n_all = resp.f, resp.acceleration
    coh = resp.coherence
    top = s.high / T
    use = (f >= s.low) & (f <= top) & (coh >= s.min_coherence) & np.isfinite(n_all)
    use &= np.abs(n_all) > 0
    exc_band = resp.excitation_band(s.band_drop)
    if use.sum() < s.min_bins:
        return FrfAnalysis(
            resp,
            (s.low, top),
            int(use.sum()),
            math.nan,
            math.nan,
            math.nan,
            None,
            reason=f'too few coherent frequencies ({use.sum()}) to see a resonance',
            excitation_band=exc_band,
        )
    w, n = 2.0 * math.pi * f[use], n_all[use]
    c = np.clip(coh[use], 0.0, 0.999)
    # the spread of log|Ĥ| and of its phase: (1 − γ²)/(2·n·γ²) (Bendat & Piersol 2010, §9.2.4)
    weight = np.sqrt(2.0 * resp.segments * c / (1.0 - c))
    band = (float(f[use].min()), float(f[use].max()))

    def res_rigid(p: np.ndarray) -> np.ndarray:
        return _residual(n, _rigid(p, w), weight)

    p0 = np.array([math.log(float(np.median(np.abs(n)))), T, math.log(5.0)])
    rigid = optimize.least_squares(res_rigid, p0, method='lm')
    dof_r = 2 * len(w) - 3
    chi_r = 2.0 * rigid.cost / dof_r

    def res_flex(p: np.ndarray) -> np.ndarray:
        return _residual(n, _two_mass(p, w), weight)

    # start from the bins that stand out of the rigid line and from bins across the band, a
    # few mass ratios and dampings; refine the best few (the fit has local minima)
    line = np.abs(n / _rigid(rigid.x, w))
    starts = np.unique(np.concatenate([w[np.argsort(line)[-5:]], w[:: max(1, len(w) // 12)]]))
    tried = []
    for wr0 in starts:
        for ratio0 in (0.1, 0.3, 1.0):
            for z0 in (0.03, 0.1):
                p1 = np.concatenate([rigid.x, np.log([ratio0, wr0, z0])])
                tried.append((float(np.sum(res_flex(p1) ** 2)), p1))
    tried.sort(key=lambda c: c[0])
    fits = [optimize.least_squares(res_flex, p1, method='lm', max_nfev=300) for _, p1 in tried[:6]]
    fit = min(fits, key=lambda r: r.cost)
    dof_f = 2 * len(w) - 6
    chi_f = 2.0 * fit.cost / dof_f
    cov = _covariance(fit.jac, chi_f)
    half = Z95 * np.sqrt(np.abs(np.diag(cov))) if cov is not None else np.full(6, np.inf)
    p = fit.x

    def log_interval(i: int) -> Interval:
        v = float(np.exp(p[i]))
        return Interval(v, v * float(np.expm1(min(half[i], 50.0))))

    cand = TwoMassModel(
        b=log_interval(0),
        mass_ratio=log_interval(3),
        omega_r=log_interval(4),
        zeta=log_interval(5),
        delay=float(p[1]),
        friction_damping=float(np.exp(p[2])),
        chi2=chi_f,
    )
    b_rigid, delay_rigid = float(np.exp(rigid.x[0])), float(rigid.x[1])
    hz = cand.resonance_hz
    rel = cand.omega_r.half_width / cand.omega_r.value
    if chi_r < s.improvement * chi_f:
        why = (
            f'a rigid line describes the response ({band[0]:.0f}-{band[1]:.0f} Hz) as well as '
            f'a two-mass model (χ² {chi_r:.3g} vs {chi_f:.3g})'
        )
        chosen = None
    elif not band[0] < hz < band[1] or cand.zeta.value > s.max_zeta or cand.peak < s.min_peak:
        why = (
            f'the response is not that of a rigid axis (χ² {chi_r:.3g}) but shows no clear '
            f'resonance in {band[0]:.0f}-{band[1]:.0f} Hz (best two-mass fit: {hz:.3g} Hz, '
            f'ζ {cand.zeta.value:.2g}, peak {cand.peak:.2g}×)'
        )
        chosen = None
    elif rel > s.max_freq_error:
        why = f'a resonance near {hz:.3g} Hz that the data do not pin (±{100 * rel:.0f} %)'
        chosen = None
    else:
        why = (
            f'a resonance at {hz:.3g} Hz, ζ ≈ {cand.zeta.value:.2g}, that a rigid model cannot '
            f'describe'
        )
        chosen = cand
    return FrfAnalysis(resp, band, len(w), b_rigid, delay_rigid, chi_r, chosen, cand, why, exc_band)


def _covariance(jac: np.ndarray, chi2: float) -> np.ndarray | None:
    try:
        return chi2 * np.linalg.inv(jac.T @ jac)
    except np.linalg.LinAlgError:
        return None
