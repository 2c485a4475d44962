"""The parameters `tune` gives an identified axis: ADRC law with the ESO, by pole placement.

The law (Beltrán 2013 eq. (9)) places the tracking-error poles at ω_c with damping ζ_c; the
extended-state observer puts its error poles at −ω_o. The bandwidths are the tuning rule's
for the sample period and the identified delay (mill_models.loop_tuning: ω_o·(N + 3/2)·T =
0.75, ω_c = ω_o/3), which keeps the margins the same at every rate; then

- the encoder: its quantization (q/√12 RMS) must not move the command by more than
  `noise_share` of the torque limit, else ω_o (and ω_c with it) comes down until it does;
- the friction and the load: the torque that balances them, (β + |γ|)/b, must leave at least
  half the torque limit to accelerate with, else the axis is refused;
- the axis as it is: the loop as built, on the response identify measured (the fitted model
  where the measurement is poor: mill_bringup.tuning.margins), must keep a gain margin of
  MIN_GAIN_MARGIN and a phase margin of MIN_MEASURED_PHASE and settle on the fitted model,
  else both bandwidths come down in steps of MARGIN_STEP until it does (`limited by:
  resonance` on a two-mass axis, `measured response` on another);
- the band measured: above the frequency up to which identify measured the response
  coherently (mill_models.frequency_response.measured_to) the margins rest on the fitted
  model alone, which cannot show a resonance there. The loop gain must have fallen to
  LOOP_FLOOR_DB within that band, else both bandwidths come down in the same steps until it
  has (`limited by: measured band`), and a note names the band, the crossover and the
  frequency it would need. With no coherent measurement at all a note says the margins are
  the model's alone.

The observer starts from the identified load (hold_torque = γ/b), so a vertical axis does not
sag when it is released, and both roles are told the identified input gain and delay.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

from mill_models.axis_model import AxisModel
from mill_models.identification import AxisIdentification
from mill_models.loop_tuning import loop_tuning

from mill_bringup.tuning.margins import Margins

ZETA_C = 0.7071  # damping of the tracking-error poles, as the papers' and the rule's
NOISE_SHARE = 0.01  # of the torque limit, RMS
TORQUE_SHARE = 0.5  # of the torque limit that friction and load may take
NOISE_STEP = 0.8  # ω_o is lowered by this factor until the noise fits
MIN_PHASE_MARGIN = 20.0  # [deg] below it the design is refused (--min-phase-margin)
MIN_GAIN_MARGIN = 6.0  # [dB] on the measured response
MIN_MEASURED_PHASE = 30.0  # [deg] on the measured response
MARGIN_STEP = 0.9  # ω_o and ω_c are lowered by this factor until the measured margins hold
# The loop must have been measured up to where its gain falls to this (on the response the
# margins are taken on): above, an unseen resonance peaking up to 20 dB over the model
# cannot make it cross 1 again (issue 32's M2 y peaks 14 dB over the rigid line)
LOOP_FLOOR_DB = -20.0


def observer_values(kind: str, omega_o: float) -> dict[str, object]:
    """The observer's own parameters at bandwidth ω_o: the ESO of degree 0 (every pole at
    −ω_o), or Beltrán's GPI observer (eq. (18) with ω_o = p_o, ζ_o = 0.7071, as the paper)."""
    if kind == 'eso':
        return {'eso.omega_o': omega_o, 'eso.degree': 0}
    if kind == 'gpi':
        return {'gpi.omega_o': omega_o, 'gpi.zeta_o': ZETA_C, 'gpi.pole_o': omega_o}
    raise TuneError(f'unknown observer {kind!r} (eso or gpi)')


def controller_values(omega_c: float) -> dict[str, object]:
    """The ADRC law's own parameters at bandwidth ω_c (Beltrán 2013 eq. (12))."""
    return {'pd.omega_c': omega_c, 'pd.zeta_c': ZETA_C}


class TuneError(ValueError):
    """The axis cannot be tuned as asked; str() says why in one line."""


@dataclass(frozen=True)
class AxisTuning:
    axis: str
    omega_o: float  # [rad/s]
    omega_c: float  # [rad/s]
    margins: Margins
    torque_noise: float  # RMS command from the encoder's quantization [N·m]
    limited_by: str  # 'rate and delay', 'encoder', 'resonance' or 'measured response'
    observer_kind: str = 'eso'
    at_rule: Margins | None = None  # on the measured response at the rule's bandwidths,
    # when they did not hold there (why the bandwidths came down)
    shaping: dict[str, object] = field(default_factory=dict)  # the controller's command
    # shaping (command_filter.*, friction_compensation.*, backlash.*)
    notes: tuple[str, ...] = ()  # what was chosen for the axis's structure, and why
    band_note: str = ''  # how the band identify measured bounds the design (printed)

    def controller(
        self, m: AxisIdentification, delay: int, torque_limit: float, following_error_limit: float
    ) -> dict[str, object]:
        return {
            'controller': 'adrc',
            'input_gain': m.b.value,
            'command_delay': delay,
            **controller_values(self.omega_c),
            'pd.torque_limit': torque_limit,
            'following_error_limit': following_error_limit,
            **self.shaping,
        }

    def observer(self, m: AxisIdentification, delay: int) -> dict[str, object]:
        return {
            'observer': self.observer_kind,
            'input_gain': m.b.value,
            'command_delay': delay,
            **observer_values(self.observer_kind, self.omega_o),
            'hold_torque': m.gamma.value / m.b.value,
        }


def check_torque(axis: str, m: AxisIdentification, torque_limit: float) -> None:
    need = (abs(m.beta.value) + abs(m.gamma.value)) / m.b.value
    if need > TORQUE_SHARE * torque_limit:
        raise TuneError(
            f'{axis}: friction and load take {need:.3g} N·m of the {torque_limit:g} N·m torque '
            f'limit (more than {100 * TORQUE_SHARE:g} %): nothing left to accelerate with'
        )


def design_axis(
    axis: str,
    m: AxisIdentification,
    T: float,
    delay: int,
    torque_limit: float,
    margins_at: Callable[[float, float], Margins],
    observer_kind: str = 'eso',
    min_phase_margin: float = MIN_PHASE_MARGIN,
    two_mass: bool = False,
    measured_to: float | None = None,
) -> AxisTuning:
    """margins_at(ω_o, ω_c): the margins of the loop built with those bandwidths (with
    `.measured`, those on the axis's response, when it has one). `two_mass`: the axis has
    a resonance (names what limits the bandwidth). measured_to: the frequency up to which
    the response was measured coherently [Hz] (None: nowhere)."""
    check_torque(axis, m, torque_limit)
    rule = loop_tuning(T, delay)
    omega_o, limited_by = rule.omega_o, 'rate and delay'
    quantization = m.resolution / math.sqrt(12.0)
    first: Margins | None = None
    short: tuple[float, float] | None = None  # (crossover, reach) [Hz] of the first design
    # whose loop gain had not fallen to LOOP_FLOOR_DB within the measured band
    for _ in range(60):
        found = margins_at(omega_o, omega_o * rule.omega_c / rule.omega_o)
        noise = found.noise_gain * quantization
        if noise > NOISE_SHARE * torque_limit:
            omega_o, limited_by = omega_o * NOISE_STEP, 'encoder'
            continue
        if found.phase < min_phase_margin:
            raise TuneError(
                f'{axis}: with the {observer_kind} observer the loop as built has a phase '
                f'margin of {found.phase:.0f}° (below {min_phase_margin:g}°): '
                f'{found.text()}; use the eso observer'
            )
        on_axis = found.measured
        if on_axis is not None and not on_axis.holds(MIN_MEASURED_PHASE, MIN_GAIN_MARGIN):
            first = first or on_axis
            omega_o = omega_o * MARGIN_STEP
            limited_by = 'resonance' if two_mass else 'measured response'
            continue
        loop = on_axis or found
        reach = loop.reach(LOOP_FLOOR_DB) / (2.0 * math.pi)
        if measured_to is not None and reach > measured_to:
            short = short or (loop.crossover / (2.0 * math.pi), reach)
            omega_o, limited_by = omega_o * MARGIN_STEP, 'measured band'
            continue
        omega_c = omega_o * rule.omega_c / rule.omega_o
        note = _band_note(measured_to, short, omega_c, loop.crossover / (2.0 * math.pi), reach)
        return AxisTuning(
            axis, omega_o, omega_c, found, noise, limited_by, observer_kind, first, band_note=note
        )
    if first is not None:
        raise TuneError(
            f'{axis}: no bandwidth keeps a gain margin of {MIN_GAIN_MARGIN:g} dB and a phase '
            f"margin of {MIN_MEASURED_PHASE:g}° on the measured response (at the rule's: "
            f'{first.text()})'
        )
    raise TuneError(
        f'{axis}: the encoder ({1e6 * m.resolution:.3g} µm) moves the command by more than '
        f'{100 * NOISE_SHARE:g} % of the torque limit at any usable bandwidth'
    )


def _band_note(
    measured_to: float | None,
    short: tuple[float, float] | None,
    omega_c: float,
    crossover: float,
    reach: float,
) -> str:
    """One line: how the band identify measured bounds the design (module doc)."""
    floor = f'{LOOP_FLOOR_DB:g} dB'
    if measured_to is None:
        return (
            'no frequency response was measured coherently: the margins are the fitted '
            f"model's alone at every frequency (the loop gain falls to {floor} by "
            f'{reach:.0f} Hz); a resonance there would not show'
        )
    if short is None:
        return (
            f'the response was measured up to {measured_to:.0f} Hz; the loop gain falls to '
            f'{floor} by {reach:.0f} Hz, within it'
        )
    return (
        f'the response was measured up to {measured_to:.0f} Hz; a design crossing at '
        f'{short[0]:.0f} Hz needs it to ~{short[1]:.0f} Hz (its loop gain down to {floor}): '
        f'bandwidths lowered to ω_c {omega_c:.1f} rad/s (crossing at {crossover:.0f} Hz, '
        f'{floor} by {reach:.0f} Hz); a longer identify run or a larger '
        'excitation.short_share measures more'
    )


# notch widths tried: a wider notch covers more of the resonance's uncertainty and shift,
# a narrower one lags less at the crossover (a width ζ lags ~2ζ·ω/ωn rad below ωn)
NOTCH_DAMPINGS = (0.05, 0.1, 0.2, 0.3)
SMOOTHING_SHARE = 0.25  # the friction feed-forward's sign smoothed over this × the Stribeck speed


def notch_values(structure: AxisModel, damping: float) -> dict[str, object]:
    """A notch on the command at the identified resonance."""
    tm = structure.two_mass
    assert tm is not None
    return {
        'command_filter.notch_frequency': tm.resonance_hz,
        'command_filter.notch_damping': damping,
    }


def friction_values(
    structure: AxisModel | None, m: AxisIdentification, omega_o: float
) -> dict[str, object]:
    """The friction feed-forward from the identified Stribeck curve, as motor torques (none
    when identify saw no Stribeck effect: the observer carries Coulomb friction as it is)."""
    fr = structure.friction if structure is not None else None
    if fr is None or not fr.present or fr.speed is None:
        return {}
    b = m.b.value
    return {
        # the curve's accelerations as the motor torques that balance them: F/b
        'friction_compensation.breakaway': fr.static.value / b,
        'friction_compensation.sliding': fr.coulomb.value / b,
        'friction_compensation.stribeck_speed': fr.speed.value,
        'friction_compensation.viscous': max(0.0, fr.viscous.value) / b,
        'friction_compensation.smoothing_speed': SMOOTHING_SHARE * fr.speed.value,
        'friction_compensation.handover': omega_o,
    }


def choose_for_resonance(
    lowered: AxisTuning, notched: AxisTuning | None, structure: AxisModel
) -> AxisTuning:
    """The design that keeps the margins with the better tracking: the higher bandwidth (a
    disturbance's tracking error falls as 1/ω_c²)."""
    tm = structure.two_mass
    hz = tm.resonance_hz if tm is not None else math.nan
    if notched is not None and notched.omega_c > lowered.omega_c * 1.001:
        zeta = notched.shaping.get('command_filter.notch_damping')
        why = (
            f'a notch at {hz:.3g} Hz (ζ {zeta}) keeps the margins at ω_c '
            f'{notched.omega_c:.1f} rad/s; without it the bandwidth must come down to '
            f'{lowered.omega_c:.1f} rad/s: the notch tracks better'
        )
        return replace(notched, notes=(*notched.notes, why))
    alt = f'a notch at {hz:.3g} Hz allows only {notched.omega_c:.1f} rad/s' if notched else ''
    why = (
        f'the bandwidth lowered to ω_c {lowered.omega_c:.1f} rad/s for the resonance at '
        f'{hz:.3g} Hz' + (f' ({alt}): no filter' if alt else '')
    )
    return replace(lowered, notes=(*lowered.notes, why))


def backlash_values(structure: AxisModel | None) -> tuple[dict[str, object], str]:
    """LinuxCNC's backlash compensation (half the gap added to the reference towards the
    motion) for an axis measured on the motor: its values and a note. An axis measured on
    the table has the gap inside its loop: no offset, and the note says so."""
    bl = structure.backlash if structure is not None else None
    if bl is None or not bl.present:
        return {}, ''
    um = 1e6 * bl.width.value
    if bl.source == 'table':
        return {}, (
            f'{um:.3g} µm of backlash seen from the table, whose position the loop is closed '
            'on: the gap is inside the loop, no reference offset (predicted with the gap)'
        )
    return {'backlash.width': bl.width.value}, (
        f'backlash compensation: half of the {um:.3g} µm gap added to the reference towards '
        'the motion at each reversal (LinuxCNC BACKLASH)'
    )
