"""What the tuned loop should track: the job run offline on the identified machine.

The simulated plant is told the identified model (mill_models.identification) as physical
parameters: with the scenario's pitch (lead a), m_e = 1/(a·b), viscous damping α·m_e,
Coulomb friction β·m_e; a load on z is its weight (carriage mass γ·m_e/g); the encoder's
resolution and the delay as identified. The scenario then runs with the tuned parameter file,
exactly as `run_scenario --params-file` will run it, and its per-axis RMS tracking error over
t >= skip is the prediction a verification run is compared with.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from mill_analysis.identify.machine_file import MachineModel
from mill_analysis.metrics import summarize
from mill_common.signals import AXES

from mill_bringup.cli import set_duration, set_timing
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.registry import job_for
from mill_bringup.scenario import Scenario, apply_params_file, load
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


def predict(
    scenario: str,
    params_file: str,
    model: MachineModel,
    delay: int,
    skip: float,
    duration: float | None = None,
    overrides: Sequence[str] = (),
) -> Prediction:
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
    job = job_for(scen)
    rec = simulate(job)
    metrics = summarize(rec, skip)
    T = job.config.sample_period
    return Prediction(
        scen.name,
        T,
        skip,
        float(rec.t[-1]),
        {m.axis: m.rms_error for m in metrics},
        {m.axis: m.max_error for m in metrics},
        [e.text() for e in rec.events],
        list(overrides),
    )
