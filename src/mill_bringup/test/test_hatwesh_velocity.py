"""Hatwesh 2013's own experiment, steps of the velocity reference (config/hatwesh_velocity.yaml),
offline (the distributed run equals it: test/test_lockstep_equality.py).

The machine PI's figures are checked against an independent model of the sampled loop
(Hatwesh eq. (1)-(3) discretised exactly, the Table 1 PI written out here); the self-tuning
PI's, which hang on the RLS, against the figures docs/papers.md prints, for the default
readings and for the others (no load term, the discrete rule); the four claims' verdicts as
the docs state them.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
from mill_analysis.papers import (
    HV_BAND,
    HV_INERTIA_CHANGE,
    HV_LOAD,
    HV_PHASES,
    phase_metrics,
    report,
    velocity_steps,
)
from mill_analysis.record import RunRecord
from mill_bringup.cli import run_parameters
from mill_bringup.docs_figures.runs import offline
from mill_bringup.job_config import build
from mill_bringup.jobs.registry import job_for

from mill_bringup import scenario

NAME = 'hatwesh_velocity'
# The docs' check of these figures (test_docs_figures.py, group hatwesh_velocity) runs on the
# same pytest-xdist worker (--dist loadgroup) and shares these runs (docs_figures.runs).
pytestmark = pytest.mark.xdist_group(NAME)


@pytest.fixture(scope='module')
def records() -> dict[str, RunRecord]:
    return {name: offline(NAME, name) for name in scenario.load(NAME).variants}


def test_the_report_knows_where_the_scenario_changes_the_plant() -> None:
    pv = scenario.load(NAME).parameters('plant')
    assert pv['load_change.time'] == HV_INERTIA_CHANGE
    assert pv['step.start_time'] == HV_LOAD[0]
    # every phase lies between the events, and each is one cycle of four steps
    assert HV_PHASES['nominal'][1] < HV_INERTIA_CHANGE < HV_PHASES['after inertia'][0]
    assert HV_PHASES['after inertia'][1] < HV_LOAD[0] < HV_PHASES['under load'][0]


def test_step_metrics_of_a_known_response() -> None:
    dt = 1e-5
    t = np.arange(100_000) * dt
    rec = RunRecord.empty(len(t), dt)
    ref = np.where(t >= 0.1, 0.01, 0.0)
    s = np.clip(t - 0.1, 0.0, None)
    # a second-order response: 1 − e^{−s/τ}(cos ωs + sin ωs/(ωτ)), τ = 2 ms, ω = 1000 rad/s
    tau, w = 2e-3, 1000.0
    v = 0.01 * (1 - np.exp(-s / tau) * (np.cos(w * s) + np.sin(w * s) / (w * tau)))
    rec['reference_velocity'][:, 0] = ref
    rec['true_velocity'][:, 0] = np.where(t >= 0.1, v, 0.0)
    (m,) = velocity_steps(rec, 0.0, 1.0, 0.02)
    # the first peak at ω s = π: overshoot e^{−π/(ωτ)}; sampled 10 µs apart the peak is
    # missed by at most ω² (dt/2)²/2 of it (curvature): 1.3e-5 relative
    assert m.time == pytest.approx(0.1) and m.size == pytest.approx(0.01)
    assert m.overshoot == pytest.approx(100 * math.exp(-math.pi / (w * tau)), rel=2e-5)
    assert 0.0 < m.settling_time < 5 * tau * math.log(50)
    assert m.iae > 0.0


def machine_pi_loop(t_end: float) -> RunRecord:
    """The nominal x drive under the Table 1 PI, written out independently of the suite:
    J ω' = K_t K_a u − B ω (eq. (2)-(3)), x = r_g θ (eq. (1)), sampled exactly (matrix
    exponential, u held over T); the velocity from the backward difference of x; the PI
    u = K_p e + I, I += K_i T e with e in motor rev/s (= table m/s ÷ pitch)."""
    T, ka, kt, b, j, pitch = 2.5e-4, 15.7311, 1.39, 14e-4, 2.8828e-3, 0.012
    kp, ki = 1.5735, 5.4976
    rg = pitch / (2 * math.pi)
    a = np.array([[0.0, 1.0, 0.0], [0.0, -b / j, kt * ka / j], [0.0, 0.0, 0.0]])
    e = scipy.linalg.expm(a * T)  # [θ, ω, u] with u held
    scen = scenario.load(NAME).variant('machine_pi')
    job = job_for(scen)
    from mill_trajectory.config import build_job

    path = build_job(scen.parameters('trajectory')).trajectory
    n = round(t_end / T) + 1
    rec = RunRecord.empty(n, T)
    state = np.zeros(3)
    x_prev, integral = 0.0, 0.0
    for k in range(n):
        x = rg * state[0]
        v_meas = 0.0 if k == 0 else (x - x_prev) / T
        x_prev = x
        ref = path.sample(k * T)
        err = (ref.velocity[0] - v_meas) / pitch
        integral += ki * T * err
        u = kp * err + integral
        rec['reference_velocity'][k, 0] = ref.velocity[0]
        rec['true_velocity'][k, 0] = rg * state[1]
        rec['torque'][k, 0] = u
        state[2] = u
        state = e @ state
    assert job.dt_ns == 250_000
    return rec


def test_machine_pi_figures_equal_an_independent_model_of_the_sampled_loop(records) -> None:
    """The plant's RK4 step (one substep) on this linear drive differs from the exact
    exponential by O((T B/J)^5) ~ 1e-20: the figures agree to rounding (1e-9)."""
    a, b = HV_PHASES['nominal']
    ours = phase_metrics(records['machine_pi'], a, b, HV_BAND)
    model = phase_metrics(machine_pi_loop(b), a, b, HV_BAND)
    assert ours.overshoot == pytest.approx(model.overshoot, rel=1e-9)
    assert ours.settling_time == model.settling_time
    assert ours.iae == pytest.approx(model.iae, rel=1e-9)
    assert ours.overshoot == pytest.approx(4.04, abs=0.005)  # the figure of the docs


# The docs' table (docs/papers.md, "Hatwesh 2013", `offline_sim hatwesh_velocity --skip 0`):
# overshoot [%], settling [ms], IAE [µm], printed to 0.01 %, 0.01 ms and 0.001 µm. The runs
# are deterministic; the tolerances are that rounding. Readings: RLS with the load term,
# the continuous phase-margin rule, the backward-difference velocity (the defaults).
DOCS = {
    ('machine_pi', 'after inertia'): (0.19, 1.50, 8.723),
    ('machine_pi', 'under load'): (0.17, 1.50, 8.421),
    ('adaptive_pi', 'nominal'): (6.66, 1.50, 6.662),
    ('adaptive_pi', 'after inertia'): (5.96, 1.50, 5.372),
    ('adaptive_pi', 'under load'): (8.10, 1.50, 8.146),
    ('adaptive_pi_pm25', 'nominal'): (62.55, 3.75, 13.127),
    ('adaptive_pi_pm25', 'after inertia'): (59.65, 3.25, 8.833),
    ('adaptive_pi_pm25', 'under load'): (63.65, 3.75, 9.230),
}

# The other readings' rows of the docs, each with the override that selects it
# (`offline_sim hatwesh_velocity --skip 0 --variant VARIANT -p x_controller.OVERRIDE`).
READING_DOCS = {
    ('adaptive_pi.load_term=false', 'adaptive_pi'): {
        'after inertia': (5.96, 1.50, 5.226),
        'under load': (20.11, 2.00, 9.373),
    },
    ('adaptive_pi.design_rule=discrete', 'adaptive_pi_pm25'): {
        'nominal': (73.65, 4.75, 13.781),
        'under load': (74.44, 4.75, 10.984),
    },
}


def assert_row(m, row: tuple[float, float, float]) -> None:
    overshoot, settling, iae = row
    assert m.overshoot == pytest.approx(overshoot, abs=0.005)
    assert m.settling_time * 1e3 == pytest.approx(settling, abs=0.005)
    assert m.iae == pytest.approx(iae, abs=5e-4)
    assert m.max_command < 10.0  # below the amplifier limit: the loop stays linear


@pytest.mark.parametrize(('variant', 'phase'), list(DOCS))
def test_phase_figures_are_those_of_the_docs(records, variant: str, phase: str) -> None:
    assert_row(phase_metrics(records[variant], *HV_PHASES[phase], HV_BAND), DOCS[variant, phase])


@pytest.mark.parametrize(('override', 'variant'), list(READING_DOCS))
def test_the_other_readings_figures_are_those_of_the_docs(override: str, variant: str) -> None:
    rec = offline(NAME, variant, (f'x_controller.{override}',))
    for phase, row in READING_DOCS[override, variant].items():
        assert_row(phase_metrics(rec, *HV_PHASES[phase], HV_BAND), row)


def test_the_claims_and_their_verdicts(records) -> None:
    scen = scenario.load(NAME)
    configs = {name: build(scen.variant(name)) for name in scen.variants}
    text = report('hatwesh_velocity', records, run_parameters(configs))
    verdicts = [line.split('": ')[1].split(' ')[0] for line in text.splitlines() if 'claim' in line]
    # φ_m 25° overshoots: agrees; better than the machine PI: no (more overshoot); copes with
    # the inertia change: yes; copes with the load torque: no, even with the load term
    assert verdicts == ['agrees', 'DISAGREES', 'agrees', 'DISAGREES']
    assert 'machine_pi' in text and 'not within 125 ms' in text
    assert (
        'reading of adaptive_pi: RLS with the load term c (adaptive_pi.load_term), '
        'phase-margin rule continuous' in text
    )
