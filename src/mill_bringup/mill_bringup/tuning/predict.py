"""What the tuned loop should track: the job run offline on the identified machine.

The simulated plant is told the identified model (mill_models.identification) as physical
parameters: with the scenario's pitch (lead a), m_e = 1/(a·b), viscous damping α·m_e,
Coulomb friction β·m_e; a load on z is its weight (carriage mass γ·m_e/g); the encoder's
resolution and the delay as identified. The scenario then runs with the tuned parameter file,
exactly as `run_scenario --params-file` will run it, and its per-axis RMS tracking error over
t >= skip is the prediction a verification run is compared with.

The simulated plant is rigid with Coulomb friction. An axis identify saw more of (a
two-mass model, Stribeck friction, backlash) is then run again alone on that structure
(mill_bringup.tuning.axis_prediction) over the job's reference and cutting force, with the
same loops, and that run is its prediction: a compliant axis's resonance or a stick-slip
cannot surprise the run that follows.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from mill_analysis.identify.machine_file import MachineModel
from mill_analysis.metrics import RunRecord, summarize
from mill_common.signals import AXES
from mill_controllers.config import build_loop
from mill_models.axis_model import TWO_MASS, AxisModel
from mill_observers.config import build_observer_loop

from mill_bringup.cli import set_duration, set_timing
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.registry import job_for
from mill_bringup.scenario import Scenario, apply_params_file, load
from mill_bringup.tuning.axis_prediction import AxisRun, axis_plant, run_axis
from mill_bringup.tuning.design import TuneError
from mill_bringup.tuning.prediction_file import Prediction

STANDARD_GRAVITY = 9.80665


def machine_overrides(scen: Scenario, plant: str, model: MachineModel) -> list[str]:
    """-p overrides that make the simulated plant the identified machine."""
    pv = scen.parameters(plant)
    lists: dict[str, list[float]] = {
        k: [float(v) for v in pv[k]]
        for k in (
            'mass',
            'screw_inertia',
            'pitch',
            'cart_damping',
            'screw_damping',
            'coulomb_friction',
        )
    }
    gravity = False
    resolution = 0.0
    for axis, m in model.axes.items():
        i = AXES.index(axis)
        lead = lists['pitch'][i] / (2.0 * math.pi)
        me = 1.0 / (lead * m.b.value)
        carriage = min(0.5 * me, lists['mass'][i])
        load = m.gamma.value * me  # [N]
        if i == 2 and m.gamma.value > m.gamma.half_width:
            carriage, gravity = load / STANDARD_GRAVITY, True
            if carriage >= me:
                raise TuneError(
                    f'z: a load of {load:.4g} N is more than the weight of the whole moving '
                    f'mass {me:.4g} kg: not a weight; the prediction cannot simulate it'
                )
        lists['mass'][i] = carriage
        lists['screw_inertia'][i] = (me - carriage) * lead * lead
        lists['cart_damping'][i] = max(0.0, m.alpha.value * me)
        lists['screw_damping'][i] = 0.0
        lists['coulomb_friction'][i] = max(0.0, m.beta.value * me)
        resolution = max(resolution, m.resolution)
    out = [f'{plant}.{k}={v!r}' for k, v in lists.items()]
    return [
        *out,
        f'{plant}.gravity={str(gravity).lower()}',
        f'{plant}.sensor_resolution={resolution!r}',
    ]


def offline_job(
    scenario: str,
    params_file: str,
    model: MachineModel,
    delay: int,
    duration: float | None = None,
    overrides: Sequence[str] = (),
) -> tuple[Scenario, RunRecord]:
    """The scenario as tuned, on the identified machine's rigid plant, and its record."""
    scen = load(scenario)
    apply_params_file(scen, params_file)
    for text in overrides:
        scen.add_override(text)
    plant = next(n.name for n in scen.nodes if n.kind.role == 'plant')
    for text in machine_overrides(scen, plant, model):
        scen.add_override(text)
    set_timing(scen, None, delay)
    if duration is not None:
        set_duration(scen, duration)
    return scen, simulate(job_for(scen))


def predict(
    scenario: str,
    params_file: str,
    model: MachineModel,
    delay: int,
    skip: float,
    duration: float | None = None,
    overrides: Sequence[str] = (),
) -> Prediction:
    scen, rec = offline_job(scenario, params_file, model, delay, duration, overrides)
    plant = next(n.name for n in scen.nodes if n.kind.role == 'plant')
    metrics = summarize(rec, skip)
    T = float(scen.parameters(plant)['sample_period'])
    rms = {m.axis: m.rms_error for m in metrics}
    peak = {m.axis: m.max_error for m in metrics}
    events = [e.text() for e in rec.events]  # mill_analysis.events, as printed
    pitch = scen.parameters(plant)['pitch']
    for axis, structure in model.structure.items():
        if axis not in model.axes or axis not in rms or not needs_structure(structure):
            continue
        lead = float(pitch[AXES.index(axis)]) / (2.0 * math.pi)
        found = structured_axis(scen, rec, axis, structure, model, lead, delay, T)
        after = rec.t >= skip
        e = found.error[after]
        e = e[np.isfinite(e)]
        rms[axis] = float(np.sqrt(np.mean(e * e))) if e.size else math.nan
        peak[axis] = float(np.abs(e).max()) if e.size else math.nan
        # the rigid plant's events of this axis are superseded by its own run
        events = [e for e in events if not e.startswith(f'{axis} axis:')]
        if found.tripped_at is not None:
            events.append(
                f'axis {axis}: following-error trip at {found.tripped_at:.3f} s, |e| = '
                f'{1e3 * abs(found.trip_error):.3f} mm > {1e3 * found.trip_limit:g} mm '
                f'(on its identified {describe(structure)})'
            )
    return Prediction(scen.name, T, skip, float(rec.t[-1]), rms, peak, events, list(overrides))


def needs_structure(structure: AxisModel) -> bool:
    """The axis has more than the rigid plant with Coulomb friction can simulate."""
    fr, bl = structure.friction, structure.backlash
    return (
        structure.model == TWO_MASS
        or (fr is not None and fr.present)
        or (bl is not None and bl.present)
    )


def describe(structure: AxisModel) -> str:
    parts = []
    if structure.model == TWO_MASS and structure.two_mass is not None:
        parts.append(f'two-mass model ({structure.two_mass.resonance_hz:.3g} Hz)')
    if structure.friction is not None and structure.friction.present:
        parts.append('Stribeck friction')
    if structure.backlash is not None and structure.backlash.present:
        parts.append(f'backlash ({1e6 * structure.backlash.width.value:.3g} µm)')
    return ' with '.join(parts) or 'model'


def structured_axis(
    scen: Scenario,
    rec: RunRecord,
    axis: str,
    structure: AxisModel,
    model: MachineModel,
    lead: float,
    delay: int,
    T: float,
) -> AxisRun:
    """The axis run alone on its identified structure, over the job's reference and force."""
    i = AXES.index(axis)
    loop = build_loop(scen.parameters(f'{axis}_controller'))
    observer = build_observer_loop(scen.parameters(f'{axis}_observer'))
    plant = axis_plant(structure, model.axes[axis], lead, delay)
    return run_axis(
        plant,
        observer,
        loop,
        rec['reference'][:, i],
        rec['reference_velocity'][:, i],
        rec['force'][:, i],
        T,
    )
