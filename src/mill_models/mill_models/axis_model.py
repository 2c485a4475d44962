"""Which model a record supports, and why (ROS-free): issue 32, machines as they are.

`identify_structure` looks at one axis's record four ways and chooses:

- the rigid fit (mill_models.identification), which refuses records it cannot describe;
- the frequency response (mill_models.frequency_response): a resonance inside the band the
  data cover makes the axis a two-mass one, whatever the rigid fit said;
- backlash (mill_models.backlash_id): from a second, table-side measurement when there is
  one, else from the record's torque reversals;
- the friction at low speed (mill_models.friction_id): breakaway and Stribeck friction,
  from the stops.

The choice, in this order: a resonance → 'two_mass' (the FRF's model); backlash → 'rigid'
with the backlash beside it (`tune` compensates the lost motion at reversals and predicts
with the gap; without a rigid fit, 'none'); a refused rigid fit → 'none'; else 'rigid',
with its low-speed friction. `reason` says why in one line, naming the effect.

A two-mass axis whose rigid fit was refused (its resonance makes the delay ambiguous) gets
the rigid fit again with the delay its response shows (`slow`): over the stretches of steady
sliding the resonance hardly acts, and that fit gives the whole axis's gain, friction and
load, which the loop `tune` designs for it needs beside the two-mass model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from mill_models.backlash_id import Backlash, BacklashSettings, estimate_backlash, lost_motion
from mill_models.frequency_response import (
    FrfAnalysis,
    FrfSettings,
    TwoMassModel,
    analyse,
    frequency_response,
)
from mill_models.friction_id import FrictionSettings, StribeckFriction, estimate_friction
from mill_models.identification import (
    AxisIdentification,
    FitSettings,
    IdentificationError,
    identify_axis,
)

RIGID, TWO_MASS, NONE = 'rigid', 'two_mass', 'none'


@dataclass(frozen=True)
class StructureSettings:
    fit: FitSettings = field(default_factory=FitSettings)
    frf: FrfSettings = field(default_factory=FrfSettings)
    friction: FrictionSettings = field(default_factory=FrictionSettings)
    backlash: BacklashSettings = field(default_factory=BacklashSettings)


@dataclass(frozen=True)
class AxisModel:
    """The model chosen for one axis, why, and everything seen on the way."""

    model: str  # RIGID, TWO_MASS or NONE (no model: `reason` says what the record shows)
    reason: str  # one line
    rigid: AxisIdentification | None  # the rigid fit, when the record gave one
    rigid_error: str = ''  # why the rigid fit was refused
    response: FrfAnalysis | None = None  # the frequency response and its models
    friction: StribeckFriction | None = None  # low-speed friction (needs the rigid fit)
    backlash: Backlash | None = None
    slow: AxisIdentification | None = None  # a two-mass axis's rigid fit at its known delay

    @property
    def fit(self) -> AxisIdentification | None:
        """The rigid fit, else the slow one: gain, friction and load of the whole axis."""
        return self.rigid if self.rigid is not None else self.slow

    @property
    def two_mass(self) -> TwoMassModel | None:
        return self.response.two_mass if self.response is not None else None

    def line(self, axis: str) -> str:
        return f'{axis}: {self.reason}'


def identify_structure(
    x: np.ndarray,
    u: np.ndarray,
    T: float,
    settings: StructureSettings | None = None,
    table: np.ndarray | None = None,
    excitation: np.ndarray | None = None,
) -> AxisModel:
    """Choose the model of an axis from positions x [m] and commands u [N·m] (u[k] answers
    x[k]) every T; `table` the table's position beside x (a linear scale) if there is one,
    `excitation` the binary torque if known (else read off u)."""
    s = settings or StructureSettings()
    x, u = np.asarray(x, float), np.asarray(u, float)
    rigid: AxisIdentification | None = None
    error = ''
    try:
        rigid = identify_axis(x, u, T, s.fit)
    except IdentificationError as exc:
        error = str(exc)
    response = None
    if len(x) >= 64 and len(x) == len(u) and np.isfinite(x).all() and np.isfinite(u).all():
        response = analyse(frequency_response(x, u, T, excitation, s.frf), s.frf)
    backlash = None
    if table is not None:
        backlash = lost_motion(x, np.asarray(table, float), T)
    elif rigid is not None:
        backlash = estimate_backlash(x, u, rigid, s.backlash)
    friction = estimate_friction(x, u, rigid, s.friction) if rigid is not None else None

    def choose(model: str, why: str) -> AxisModel:
        return AxisModel(model, why, rigid, error, response, friction, backlash)

    if response is not None and response.two_mass is not None:
        chosen = choose(TWO_MASS, f'two-mass model: {response.reason}')
        if rigid is not None:
            return chosen
        # the resonance leaves more than the encoder's noise: that is the two-mass model's
        known = replace(s.fit, delay=round(response.two_mass.delay / T), max_noise=math.inf)
        try:
            return replace(chosen, slow=identify_axis(x, u, T, known))
        except IdentificationError:
            return chosen
    if backlash is not None and backlash.present:
        if rigid is None:
            return choose(NONE, backlash.reason)
        # the rigid model with the gap beside it: `tune` compensates and predicts with both
        return choose(RIGID, f'rigid with {backlash.reason}')
    if rigid is None:
        why = error
        if (
            response is not None
            and response.candidate is not None
            and response.rigid_chi2 > (s.frf.improvement * response.candidate.chi2)
        ):
            why += f' (its frequency response: {response.reason})'
        return choose(NONE, why)
    notes = []
    if response is not None and response.bins:
        lo, hi = response.band
        notes.append(f'no resonance in {lo:.0f}-{hi:.0f} Hz')
    if backlash is not None:
        notes.append('no backlash')
    if friction is not None:
        notes.append(friction.reason if friction.present else 'no Stribeck effect')
    return choose(RIGID, 'rigid: ' + '; '.join(notes))
