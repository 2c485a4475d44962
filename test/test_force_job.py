"""The Rubio 2013 force job across processes (issue 4), in a private domain on loopback.

- One point of the J_c sweep (β = −0.3) and scheme 1 run distributed: the force samples,
  overrides and active β equal the offline loop's, and J_c computed from the recorded force
  stream equals the offline J_c.
- The force controller node driven by hand: a NaN force sample is held and an override the
  law wants outside the range (0.3: too slow for the reference force) is clamped; neither
  reaches /mill/feed_override, and both are reported on /diagnostics.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import WrenchStamped
from mill_analysis.bag_run import read_run
from mill_analysis.force_record import read_force_run
from mill_analysis.report.kinds import ForceRecords, kind_of
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.registry import job_for
from mill_common.ros import DATA_QOS, from_stamp, to_stamp
from mill_common.timebase import sample_stamp_ns
from mill_controllers.force_control import ForceFeedLoop, parameter_specs
from sensor_msgs.msg import JointState

from mill_bringup import scenario
from mill_common import topics
from test.conftest import EXTENDED, busy_cores, ros_node, run_scenario, spin_until

T = 60.0 / 715.0


@pytest.mark.system
@pytest.mark.parametrize('name', [pytest.param('beta_neg0.3', marks=EXTENDED), 'scheme1'])
def test_distributed_force_job_equals_the_offline_loop(ros_env, tmp_path, name: str) -> None:
    out = tmp_path / 'run'
    proc = run_scenario(
        ros_env,
        *('rubio', '--variant', name, '--compare-offline', '--quiet', '--output', str(out)),
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    summary = json.loads((out / name / 'summary.json').read_text())
    assert summary['samples'] == 120  # 10 s of 715 rpm revolutions
    d = summary['differences']
    # Same arithmetic on both sides, except the feed's trip through the reference in m/s
    # (o·p' then ×1000 instead of o·10 mm/s): rounding, so 1e-9 of ~1e3 N or mm/s is loose.
    assert d['force'] <= 1e-9 and d['override'] <= 1e-12 and d['slope'] <= 1e-9
    assert d['beta'] == 0.0 and d['feed_command'] <= 1e-9
    # The recorded stream has whole-ns stamps: each grid time moves by <= 0.5 ns of a
    # T/32 = 2.6 ms spacing (2e-7), which bounds the change of the Simpson sums.
    assert d['j_c_relative'] <= 1e-6
    offline = simulate(job_for(scenario.load('rubio').variant(name)))
    assert summary['j_c'] == pytest.approx(offline.j_c, rel=1e-6)
    # scheme 1 switches (β 0 → −1 on this job); the run published every switch
    assert summary['beta_switches'] == int(np.count_nonzero(np.diff(offline.beta)))
    if name == 'scheme1':
        assert summary['beta_switches'] >= 1


@pytest.mark.system
def test_adaptive_feed_job_equals_its_offline_twin_and_ends_with_its_path(ros_env, tmp_path):
    """The Kline job with the force law in lockstep, on a 1 mm cut: the run's length is found
    by the trajectory (the force law slows the feed), and every sample and control instant
    equals the offline twin's."""
    segments = 'trajectory.program.segments=["linear -0.075 -0.104 -0.005 0.003"]'
    out = tmp_path / 'run'
    proc = run_scenario(
        ros_env,
        *('slotting_adaptive_feed', '-p', segments, '--compare-offline', '--quiet'),
        *('--output', str(out), '--record', str(tmp_path / 'bag')),
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    summary = json.loads((out / 'summary.json').read_text())
    scen = scenario.load('slotting_adaptive_feed')
    scen.add_override(segments)
    job = job_for(scen)
    nominal = job.samples  # at override 1
    offline = simulate(job)
    assert summary['samples'] == len(offline.t) == job.samples != nominal
    assert summary['missing_samples'] == {}
    # the same cores on the same floats: bit-equal on every quantity, as docs/papers.md says
    assert summary['offline_max_difference'] == 0.0
    assert set(summary['differences']) >= {'tracking_error', 'force_control.override'}
    assert set(summary['differences'].values()) == {0.0}
    # its bag: `report` finds the job's length from the "done" status, and the overrides
    run = read_run(tmp_path / 'bag')
    assert run.n == job.samples and run.job_end_source == 'job status on /diagnostics'
    overrides = [v for _, v in run.feed_override]  # the graph ran on until it was stopped
    assert overrides[: len(offline.force_control)] == offline.force_control[:, 4].tolist()


@pytest.mark.system
@pytest.mark.serial  # two busy loops: alone on the machine (scripts/test.sh)
@pytest.mark.parametrize(
    'busy', [pytest.param(0, marks=EXTENDED), 2], ids=['quiet', 'both_cores_busy']
)
def test_report_computes_j_c_from_a_force_jobs_bag(ros_env, tmp_path, busy: int) -> None:
    """Also with both cores busy (issue 21): the force process steps at most its
    recorder_window ahead of the revolutions the runner has recorded whole, so a loaded
    machine slows the run down and its bag misses nothing."""
    out, bag = tmp_path / 'run', tmp_path / 'bag'
    with busy_cores(busy):
        proc = run_scenario(
            ros_env,
            *('rubio', '--variant', 'scheme1', '--quiet', '--output', str(out)),
            *('--record', str(bag)),
        )
    assert proc.returncode == 0, proc.stderr[-3000:]
    summary = json.loads((out / 'scheme1' / 'summary.json').read_text())
    assert summary['missing_samples'] == {}
    report = subprocess.run(
        [sys.executable, '-m', 'mill_analysis.report', str(bag / 'scheme1'), '--out', str(out)],
        env=ros_env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert report.returncode == 0, report.stderr[-3000:]
    assert 'J_c [N² s]' in report.stdout and (out / 'force.png').is_file()
    assert isinstance(kind_of(bag / 'scheme1'), ForceRecords)  # as the runner named it
    run = read_force_run(bag / 'scheme1')
    assert run.samples == summary['samples'] and not run.missing and not run.notes
    # The same stream, the same reference model (ξ, ω_n from the controller's state), the
    # period estimated from the stamps to well below 1 ns: the same sum to rounding.
    assert run.record.j_c == pytest.approx(summary['j_c'], rel=1e-12)


def _force(ns: int, value: float) -> WrenchStamped:
    msg = WrenchStamped()
    msg.header.stamp = to_stamp(ns)
    msg.wrench.force.x = value
    return msg


@pytest.mark.system
def test_nan_force_is_held_and_overrides_are_clamped(start_node) -> None:
    ctrl = start_node(
        'mill_controllers.force_controller_node',
        'force_controller',
        *('-p', 'force_controller:force_control.beta:=-0.3'),
        *('-p', 'force_controller:override.max:=0.3'),
        params_file=False,
    )
    overrides: dict[int, tuple[float, float]] = {}
    warnings: list[str] = []

    def on_override(msg: JointState) -> None:
        overrides[from_stamp(msg.header.stamp)] = (msg.position[0], msg.velocity[0])

    def on_diagnostics(msg: DiagnosticArray) -> None:
        warnings.extend(s.message for s in msg.status if s.level == DiagnosticStatus.WARN)

    with ros_node('force_tester') as (node, executor):
        node.create_subscription(JointState, topics.FEED_OVERRIDE, on_override, DATA_QOS)
        node.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, on_diagnostics, 100)
        force = node.create_publisher(WrenchStamped, topics.CUTTING_FORCE, DATA_QOS)

        assert spin_until(
            executor,
            lambda: (
                force.get_subscription_count() > 0
                and node.count_publishers(topics.FEED_OVERRIDE) > 0
            ),
            60,
        ), 'force controller never matched'
        spin_until(executor, lambda: False, 0.5)

        def sample(k: int, value: float) -> tuple[float, float]:
            ns = sample_stamp_ns(k, T)
            force.publish(_force(ns, value))
            assert spin_until(executor, lambda: ns in overrides), f'no override for sample {k}'
            return overrides[ns]

        forces = [0.0, 600.0, math.nan, 1200.0, 1500.0]
        got = [sample(k, f) for k, f in enumerate(forces)]
        assert spin_until(executor, lambda: any('non-finite force' in w for w in warnings))
        assert any('outside [0, 0.3]' in w for w in warnings), warnings
    assert ctrl.alive()
    # The same samples through the same loop offline, with the NaN replaced by 600 N.
    values = {name: spec.default for name, spec in parameter_specs()}
    values.update({'force_control.beta': -0.3, 'override.max': 0.3})
    held, plain = ForceFeedLoop.from_parameters(values), ForceFeedLoop.from_parameters(values)
    want = [held.step(k * T, 1200.0, f) for k, f in enumerate(forces)]
    same = [plain.step(k * T, 1200.0, f) for k, f in enumerate([0.0, 600.0, 600.0, 1200.0, 1500.0])]
    assert got == [(c.override, c.slope) for c in want] == [(c.override, c.slope) for c in same]
    # 3 mm/s cannot make 1200 N: the law asks for more and gets the range's top
    assert any(c.override == 0.3 and c.feed_command > 3.0 for c in want)
    assert all(0.0 <= o <= 0.3 and math.isfinite(s) for o, s in got)
