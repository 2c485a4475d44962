"""What the controller does to the law's command before it is sent (ROS-free).

Two optional stages, both off by default (every parameter 0), which `tune` sets from the
identified machine (docs/bring-up.md):

- friction compensation: the identified friction at the reference speed v_r, as the motor
  torque that balances it,
      u_f(v) = tanh(v/v_s)·(F_c + (F_s − F_c)·exp(−(v/v_St)²)) + σ·v
  (the Stribeck curve of Olsson et al. 1998 §2 with δ = 2, as mill_models.friction_id fits
  it, its sign smoothed through zero speed over v_s so that a reversal gives no torque step),
  is added to the law's command for as long as the observer has not learnt it: the
  observer is told the whole command, so its disturbance estimate, which the law cancels,
  comes to hold the friction the feed-forward holds; the feed-forward is therefore handed
  over to it, high-passed at the observer's bandwidth ω_h (`handover`): u_f − LP_ωh(u_f).
  What it adds is the friction's changes (breakaway, the Stribeck drop, reversals) before
  the observer can see them;
- backlash compensation: half the identified gap is added to the reference the law tracks,
  in the direction the reference moves, ramped over `backlash.ramp_time` at each reversal
  (LinuxCNC's BACKLASH);
- a command filter: a notch at an axis resonance and/or a second-order low-pass, each a
  biquad from its continuous prototype by the bilinear transform pre-warped at its
  frequency (so the notch sits exactly where it is asked for).

The filter acts on the sum (law + feed-forward), which is what the drive gets; the observer
is told that command, as it is told every command.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from mill_common.declared import ParamSet, param
from mill_common.parameters import ParameterError, non_negative, positive


def _share(value: float) -> str | None:
    return None if 0.0 <= value <= 1.0 else 'must be within 0 and 1'


@dataclass(frozen=True)
class CommandFilterParams(ParamSet):
    PREFIX: ClassVar[str] = 'command_filter'
    notch_frequency: float = param(
        0.0,
        'centre of a notch filter on the command, at an axis resonance; 0 = no notch',
        non_negative,
        unit='Hz',
        read_only=True,
    )
    notch_damping: float = param(
        0.3,
        "damping ratio of the notch's poles: its width",
        positive,
        unit='-',
        read_only=True,
    )
    notch_depth: float = param(
        0.0,
        'the gain the notch leaves at its centre (0: all of it is taken out)',
        _share,
        unit='-',
        read_only=True,
    )
    lowpass_frequency: float = param(
        0.0,
        'corner of a second-order low-pass filter (damping 0.7071) on the command; 0 = none',
        non_negative,
        unit='Hz',
        read_only=True,
    )

    @property
    def active(self) -> bool:
        return self.notch_frequency > 0.0 or self.lowpass_frequency > 0.0


@dataclass(frozen=True)
class FrictionCompensationParams(ParamSet):
    PREFIX: ClassVar[str] = 'friction_compensation'
    breakaway: float = param(
        0.0,
        'static (breakaway) friction as the motor torque that balances it; 0 with sliding '
        'and viscous 0 = no compensation',
        non_negative,
        unit='N·m',
        read_only=True,
    )
    sliding: float = param(
        0.0,
        'sliding (Coulomb) friction as the motor torque that balances it',
        non_negative,
        unit='N·m',
        read_only=True,
    )
    stribeck_speed: float = param(
        0.002,
        'speed over which friction falls from breakaway to sliding',
        positive,
        unit='m/s',
        read_only=True,
    )
    viscous: float = param(
        0.0,
        'viscous friction as the motor torque per speed',
        non_negative,
        unit='N·m·s/m',
        read_only=True,
    )
    smoothing_speed: float = param(
        0.0005,
        'the sign of the friction is smoothed through zero speed over this speed',
        positive,
        unit='m/s',
        read_only=True,
    )
    handover: float = param(
        0.0,
        "the observer's bandwidth: the feed-forward is handed over to the observer's "
        'disturbance estimate at it (high-passed), so that the two do not compensate the '
        'friction twice; 0 = never (a law without a disturbance observer)',
        non_negative,
        unit='rad/s',
        read_only=True,
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.breakaway and self.breakaway < self.sliding:
            raise ParameterError(
                'friction_compensation.breakaway',
                self.breakaway,
                f'below friction_compensation.sliding = {self.sliding!r}',
            )

    @property
    def active(self) -> bool:
        return self.breakaway > 0.0 or self.sliding > 0.0 or self.viscous > 0.0

    def torque(self, v: float) -> float:
        """The feed-forward at reference speed v [N·m]."""
        fs = max(self.breakaway, self.sliding)
        level = self.sliding + (fs - self.sliding) * math.exp(-((v / self.stribeck_speed) ** 2))
        # u_f = tanh(v/v_s)·(F_c + (F_s − F_c)·e^(−(v/v_St)²)) + σ·v
        return math.tanh(v / self.smoothing_speed) * level + self.viscous * v


@dataclass(frozen=True)
class BacklashParams(ParamSet):
    PREFIX: ClassVar[str] = 'backlash'
    width: float = param(
        0.0,
        'lost motion at a reversal: half of it is added to the reference in the direction '
        'of motion (LinuxCNC BACKLASH); 0 = none',
        non_negative,
        unit='m',
        read_only=True,
    )
    ramp_time: float = param(
        0.02,
        'the compensation moves from one side to the other over this time',
        positive,
        unit='s',
        read_only=True,
    )
    min_speed: float = param(
        1e-4,
        'a reference slower than this keeps the side it was on',
        positive,
        unit='m/s',
        read_only=True,
    )

    @property
    def active(self) -> bool:
        return self.width > 0.0


class Biquad:
    """y = (b0 + b1 z⁻¹ + b2 z⁻²)/(1 + a1 z⁻¹ + a2 z⁻²) u (direct form II transposed)."""

    def __init__(self, num: tuple[float, float, float], den: tuple[float, float, float]) -> None:
        self.b0, self.b1, self.b2 = (v / den[0] for v in num)
        self.a1, self.a2 = den[1] / den[0], den[2] / den[0]
        self.s1 = self.s2 = 0.0

    @classmethod
    def bilinear(
        cls, num: tuple[float, float, float], den: tuple[float, float, float], w: float, T: float
    ) -> Biquad:
        """From (n0 s² + n1 s + n2)/(d0 s² + d1 s + d2), pre-warped at ω [rad/s]."""
        # s = K (z − 1)/(z + 1), K = ω / tan(ωT/2): exact at ω
        K = w / math.tan(0.5 * w * T)

        def digital(c: tuple[float, float, float]) -> tuple[float, float, float]:
            k2, k1 = c[0] * K * K, c[1] * K
            return k2 + k1 + c[2], 2.0 * (c[2] - k2), k2 - k1 + c[2]

        return cls(digital(num), digital(den))

    def step(self, u: float) -> float:
        y = self.b0 * u + self.s1
        self.s1 = self.b1 * u - self.a1 * y + self.s2
        self.s2 = self.b2 * u - self.a2 * y
        return y

    def reset(self) -> None:
        self.s1 = self.s2 = 0.0


LOWPASS_DAMPING = 0.7071


def command_filters(p: CommandFilterParams, T: float) -> list[Biquad]:
    """The biquads of the command filter at sample period T (ParameterError when a frequency
    is not below the Nyquist frequency)."""
    out = []
    nyquist = 0.5 / T
    for name, f in (
        ('notch_frequency', p.notch_frequency),
        ('lowpass_frequency', p.lowpass_frequency),
    ):
        if f >= nyquist:
            raise ParameterError(
                f'command_filter.{name}', f, f'not below the Nyquist frequency {nyquist:g} Hz'
            )
    if p.notch_frequency > 0.0:
        w = 2.0 * math.pi * p.notch_frequency
        z = p.notch_damping
        # N(s) = (s² + 2·d·ζ·ω·s + ω²)/(s² + 2·ζ·ω·s + ω²): gain d at ω, 1 far from it
        out.append(
            Biquad.bilinear(
                (1.0, 2.0 * p.notch_depth * z * w, w * w), (1.0, 2.0 * z * w, w * w), w, T
            )
        )
    if p.lowpass_frequency > 0.0:
        w = 2.0 * math.pi * p.lowpass_frequency
        # F(s) = ω²/(s² + 2·ζ·ω·s + ω²)
        out.append(
            Biquad.bilinear((0.0, 0.0, w * w), (1.0, 2.0 * LOWPASS_DAMPING * w, w * w), w, T)
        )
    return out


class CommandShaping:
    """The stages above for one axis, stepped once per sample."""

    def __init__(
        self,
        sample_period: float,
        filters: CommandFilterParams = CommandFilterParams(),
        friction: FrictionCompensationParams = FrictionCompensationParams(),
        backlash: BacklashParams = BacklashParams(),
    ) -> None:
        self.friction = friction
        self.backlash = backlash
        self.filters = command_filters(filters, sample_period)
        self._T = sample_period
        self._side = 0.0  # the backlash compensation's side, −1 … 1 (ramped)
        # the share of the feed-forward the observer has learnt per sample: 1 − e^(−ω_h·T)
        self._learn = -math.expm1(-friction.handover * sample_period)
        self._learnt = 0.0

    @property
    def active(self) -> bool:
        return bool(self.filters) or self.friction.active or self.backlash.active

    def offset(self, velocity: float) -> float:
        """The backlash compensation to add to the reference at reference speed `velocity`
        [m]; call once per sample."""
        if not self.backlash.active:
            return 0.0
        b = self.backlash
        if abs(velocity) > b.min_speed:
            step = 2.0 * self._T / b.ramp_time  # from −1 to 1 over ramp_time
            target = math.copysign(1.0, velocity)
            self._side += max(-step, min(step, target - self._side))
        # LinuxCNC BACKLASH: half the width on the side the reference moves towards
        return 0.5 * b.width * self._side

    def command(self, effort: float, velocity: float) -> float:
        """The command sent for the law's `effort` at reference speed `velocity`."""
        u = effort
        if self.friction.active:
            ff = self.friction.torque(velocity)
            u += ff - self._learnt
            # LP_ωh(u_f): what the observer's estimate holds of it by the next sample
            self._learnt += self._learn * (ff - self._learnt)
        for f in self.filters:
            u = f.step(u)
        return u

    def reset(self) -> None:
        for f in self.filters:
            f.reset()
