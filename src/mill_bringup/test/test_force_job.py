"""Force-job scenarios and the J_c analysis of a recorded force stream (ROS-free)."""

from __future__ import annotations

import numpy as np
import pytest
from mill_bringup.force_record import continuous_cost, smooth_pieces
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.force import ForceJob
from mill_bringup.jobs.registry import job_for

from mill_bringup import scenario

RUBIO = ('zoh', 'beta_neg0.3', 'scheme1', 'scheme2')


def rubio(variant: str) -> scenario.Scenario:
    return scenario.load('rubio').variant(variant)


@pytest.mark.parametrize('name', RUBIO)
def test_rubio_variants_are_consistent_force_jobs(name: str) -> None:
    job = job_for(rubio(name))
    assert isinstance(job, ForceJob)
    assert job.samples == 120 and job.period == 60.0 / 715.0
    assert job.controller_values['reference_force'] == 1200.0


def test_cost_from_the_stream_equals_the_loop_cost() -> None:
    job = job_for(rubio('beta_neg0.3'))
    rec = simulate(job)
    design = job.design()
    j_c = continuous_cost(rec.trace_ns, rec.trace_force, 1200.0, design.damping, design.omega_n)
    assert j_c == pytest.approx(rec.j_c, rel=1e-7)
    # a stream that follows the reference model exactly costs nothing
    times = np.linspace(0.0, 1.0, 65)
    from mill_models.reference_model import ContinuousReference

    ref = ContinuousReference(design.damping, design.omega_n)
    ref.begin(1200.0)
    exact = ref.values(times)
    ns = np.rint(times * 1e9).astype(np.int64)
    assert continuous_cost(ns, exact, 1200.0, design.damping, design.omega_n) < 1e-12
    assert continuous_cost(ns, exact + 10.0, 1200.0, design.damping, design.omega_n) == (
        pytest.approx(100.0, rel=1e-9)
    )


def test_pieces_split_at_repeated_points() -> None:
    ns = np.array([0, 10, 20, 20, 30, 40, 41, 50, 60])
    pieces = smooth_pieces(ns, np.arange(9.0))
    assert [len(t) for t, _ in pieces] == [3, 3, 3]
    assert pieces[1][1].tolist() == [3.0, 4.0, 5.0]


def test_plant_and_controller_must_share_the_process_model() -> None:
    scen = rubio('zoh')
    scen.add_override('force_controller.force_process.flutes=2')
    with pytest.raises(scenario.ScenarioError, match='flutes'):
        job_for(scen)
    scen = rubio('zoh')
    scen.add_override('force_process.feed_limits=[0.0, 30.0]')
    with pytest.raises(scenario.ScenarioError, match='feed_limits'):
        job_for(scen)


def test_state_windows_average_a_recorded_run(tmp_path) -> None:
    from mill_bag.types import typestore
    from mill_bag.writer import BagWriter
    from mill_bringup.force_windows import main, state_windows

    from mill_common import topics

    store = typestore()
    js, time_msg, head = (
        store.types[n]
        for n in (
            'sensor_msgs/msg/JointState',
            'builtin_interfaces/msg/Time',
            'std_msgs/msg/Header',
        )
    )
    w = BagWriter(tmp_path / 'bag')
    state = w.add_topic(
        topics.qualify(topics.FORCE_CONTROL_STATE), 'sensor_msgs/msg/JointState', []
    )
    names = ['force', 'reference', 'feed_command', 'override', 'beta', 'depth']
    for k in range(20):  # 0.1 s apart: force k, override k/100
        ns = k * 100_000_000
        msg = js(
            header=head(stamp=time_msg(sec=ns // 10**9, nanosec=ns % 10**9), frame_id=''),
            name=names,
            position=np.array([k, 300.0, 0.0, k / 100, 0.0, 5.0]),
            velocity=np.zeros(0),
            effort=np.zeros(0),
        )
        w.write(state, ns, ns, bytes(store.serialize_cdr(msg, 'sensor_msgs/msg/JointState')))
    w.close()
    rows = state_windows(tmp_path / 'bag', [0.0, 1.0, 1.5, 5.0])
    assert [r[2] for r in rows] == [10, 5, 5]
    assert rows[0][3] == pytest.approx(4.5) and rows[0][4] == pytest.approx(0.045)
    assert rows[1][3] == pytest.approx(12.0) and rows[2][3] == pytest.approx(17.0)
    assert main([str(tmp_path / 'bag'), '0', '1']) == 0
    assert main([str(tmp_path / 'missing'), '0', '1']) == 1
