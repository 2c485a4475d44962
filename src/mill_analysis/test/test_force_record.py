"""The record of a force job: J_c of Rubio 2013 eq. (14) from a recorded force stream."""

from __future__ import annotations

import numpy as np
import pytest
from mill_analysis.force_record import continuous_cost, smooth_pieces
from mill_models.reference_model import ContinuousReference

DAMPING, OMEGA_N = 0.7, 2.5 / (3 * 60.0 / 715.0)  # Rubio 2013 §2.3 defaults at 715 rpm


def test_a_stream_that_follows_the_reference_model_costs_nothing() -> None:
    times = np.linspace(0.0, 1.0, 65)
    ref = ContinuousReference(DAMPING, OMEGA_N)
    ref.begin(1200.0)
    exact = ref.values(times)
    ns = np.rint(times * 1e9).astype(np.int64)
    assert continuous_cost(ns, exact, 1200.0, DAMPING, OMEGA_N) < 1e-12
    assert continuous_cost(ns, exact + 10.0, 1200.0, DAMPING, OMEGA_N) == (
        pytest.approx(100.0, rel=1e-9)
    )


def test_pieces_split_at_repeated_points() -> None:
    ns = np.array([0, 10, 20, 20, 30, 40, 41, 50, 60])
    pieces = smooth_pieces(ns, np.arange(9.0))
    assert [len(t) for t, _ in pieces] == [3, 3, 3]
    assert pieces[1][1].tolist() == [3.0, 4.0, 5.0]


def test_the_samples_a_force_record_lacks_are_named_and_reported() -> None:
    from mill_analysis.force_record import FORCE_TOPICS, ForceBagRun, record_from_messages
    from mill_analysis.report.force import force_table
    from mill_bag.types import typestore
    from mill_common.timebase import sample_stamp_ns

    from mill_common import topics

    ts = typestore()
    t = ts.types
    period, n = 60.0 / 7000.0, 12

    def header(k: int):
        ns = sample_stamp_ns(k, period)
        stamp = t['builtin_interfaces/msg/Time'](sec=ns // 10**9, nanosec=ns % 10**9)
        return t['std_msgs/msg/Header'](stamp=stamp, frame_id='')

    def ser(msg) -> bytes:
        return bytes(ts.serialize_cdr(msg, msg.__msgtype__))

    def force(k: int) -> bytes:
        v3 = t['geometry_msgs/msg/Vector3']
        w = t['geometry_msgs/msg/Wrench'](force=v3(x=1.0 * k, y=0, z=0), torque=v3(x=0, y=0, z=0))
        return ser(t[FORCE_TOPICS[topics.CUTTING_FORCE]](header=header(k), wrench=w))

    def joint_state(k: int, values: list[float]) -> bytes:
        arr = np.array(values, dtype=np.float64)
        return ser(
            t['sensor_msgs/msg/JointState'](
                header=header(k), name=[], position=arr, velocity=arr[:1], effort=arr[:0]
            )
        )

    def trace(k: int) -> bytes:
        point = t['trajectory_msgs/msg/JointTrajectoryPoint'](
            positions=np.array([1.0]),
            velocities=np.array([], dtype=np.float64),
            accelerations=np.array([], dtype=np.float64),
            effort=np.array([], dtype=np.float64),
            time_from_start=t['builtin_interfaces/msg/Duration'](sec=0, nanosec=0),
        )
        msg = t['trajectory_msgs/msg/JointTrajectory'](
            header=header(k), joint_names=['f'], points=[point]
        )
        return ser(msg)

    # The bag was cut after sample 7; the override of sample 2 was lost.
    kept = range(8)
    raw = {
        topics.CUTTING_FORCE: [force(k) for k in kept],
        topics.CUTTING_FORCE_TRACE: [trace(k) for k in kept],
        topics.FEED_OVERRIDE: [joint_state(k, [1.0]) for k in kept if k != 2],
        topics.FORCE_CONTROL_STATE: [joint_state(k, [1.0] * 6) for k in kept],
    }
    rec, missing = record_from_messages(raw, n, period, 'x')
    assert missing == {
        topics.CUTTING_FORCE: 4,
        topics.CUTTING_FORCE_TRACE: 4,
        topics.FEED_OVERRIDE: 5,
        topics.FORCE_CONTROL_STATE: 4,
    }
    assert rec.gaps[topics.FEED_OVERRIDE] == [(2, 2), (8, 11)]
    run = ForceBagRun('bag', rec, period, n, 1000.0, 0.7, 100.0, missing, 32)
    assert run.held == 8
    text = force_table([('cut', run)])
    assert text.splitlines()[2].split()[:2] == ['cut', '8/12']  # the row: held of the job's
    assert (
        f'cut: WARNING: {topics.FEED_OVERRIDE}: samples missing in the record: 5 (k = 2, 8–11)'
        in text.splitlines()
    )
