"""Bags of another writer (rosbags, MCAP and sqlite3) give the RunRecord they were written
from; the record built in two processes is the one built in one."""

from __future__ import annotations

import math

import numpy as np
import pytest
from builtin_interfaces.msg import Duration
from mill_analysis.bag_run import read_run
from mill_analysis.lockstep_record import build_record, record_from_raw, record_topics
from mill_analysis.metrics import summarize
from mill_analysis.node_intake import Received, subset
from mill_analysis.record import SIGNALS
from mill_bag.errors import BagError
from mill_bag.reader import open_bag
from mill_common.signals import AXES
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from mill_common import topics


@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_a_bag_of_another_writer_gives_the_record_it_holds(foreign_bag, storage) -> None:
    path, rec = foreign_bag(storage)
    run = read_run(path)
    assert (run.n, run.dt_ns, run.axes) == (rec.t.size, 1_000_000, ['x', 'y', 'z'])
    assert run.missing == {}
    np.testing.assert_array_equal(run.record.t, rec.t)
    for name in SIGNALS:
        np.testing.assert_array_equal(run.record[name], rec[name], err_msg=name)
    assert summarize(run.record, 0.1) == summarize(rec, 0.1)
    assert run.feed_override is None
    if storage == 'mcap':  # rosbags writes publish time = log time = the receive time
        assert run.state_wall_ns is not None and run.state_wall_ns[1] - run.state_wall_ns[0] > 0


def test_the_record_counts_every_listened_topic_in_the_order_the_bag_holds(foreign_bag) -> None:
    path, rec = foreign_bag('mcap')
    raw = Received()
    for topic, _type, _log, _pub, data in open_bag(path).read():
        relative = topic.removeprefix('/')
        raw.setdefault(relative, []).append(data)
        raw.order.append(relative)
    types = record_topics(AXES)
    listened = subset(raw, types)
    got, missing = record_from_raw(listened, types, AXES, 401, 1_000_000)
    # every per-sample topic, commands too, and the reference: no sample missing
    assert missing == dict.fromkeys(types, 0)
    assert got.foreign == {} and got.gaps == {}
    for name in SIGNALS:
        np.testing.assert_array_equal(got[name], rec[name], err_msg=name)


def test_a_namespaced_run_reads_as_the_root_one(foreign_bag) -> None:
    path, rec = foreign_bag('mcap', namespaces=('/machine2',))
    run = read_run(path)
    assert (run.n, run.axes, run.missing) == (rec.t.size, ['x', 'y', 'z'], {})
    for name in SIGNALS:
        np.testing.assert_array_equal(run.record[name], rec[name], err_msg=name)
    assert run.job_end_source == 'job status on /diagnostics'


def test_a_bag_of_two_machines_needs_a_namespace(foreign_bag) -> None:
    # The other machine's job status comes first, with a wrong end_time: it must be ignored.
    path, rec = foreign_bag('mcap', namespaces=('/a', '/b'), foreign_status=True)
    with pytest.raises(BagError, match=r'several namespaces \(/a, /b\); choose one'):
        read_run(path)
    with pytest.raises(BagError, match='no mill run in namespace /c'):
        read_run(path, 'c')
    for space in ('a', '/b'):
        run = read_run(path, space)
        assert run.n == rec.t.size  # from this machine's end_time, not /other's 0.1 s
        for name in SIGNALS:
            np.testing.assert_array_equal(run.record[name], rec[name], err_msg=name)


def _state(ns: int, names: list[str], position: list[float], sender: str = 'plant'):
    msg = JointState(name=names, position=position)
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(ns, 1_000_000_000)
    msg.header.frame_id = sender
    return msg


def _reference(ns: int, offsets_ns: list[int], x: float, sender: str = 'trajectory'):
    msg = JointTrajectory(joint_names=['x'])
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(ns, 1_000_000_000)
    msg.header.frame_id = sender
    for o in offsets_ns:
        d = Duration(sec=o // 1_000_000_000, nanosec=o % 1_000_000_000)
        msg.points.append(JointTrajectoryPoint(positions=[x], velocities=[0.0], time_from_start=d))
    return msg


def test_the_record_keeps_the_first_message_and_leaves_out_malformed_ones() -> None:
    T = 1_000_000
    state, ref = topics.state('x'), topics.REFERENCE
    messages = [
        (state, _state(0, ['x'], [1.0])),
        (state, _state(0, ['x'], [9.0])),  # a repeat with other values: the first counts
        (state, _state(T, ['w'], [9.0])),  # no joint x: malformed
        (state, _state(T, ['x'], [2.0], sender='intruder')),  # foreign
        (state, _state(T, ['y', 'x'], [9.0, 2.0])),
        (state, _state(2 * T, ['x'], [math.nan])),  # not finite: malformed, not the first
        (ref, _reference(T, [0, T], 5.0)),
        (ref, _reference(0, [0, T, 2 * T], 9.0)),  # in the past: left out
        (ref, _reference(2 * T, [0, T // 2], 9.0)),  # a point off the grid: malformed
        (ref, _reference(2 * T, [0], math.inf)),  # not finite: malformed, not the first
        (ref, _reference(2 * T, [0], 7.0, sender='intruder')),  # foreign
        (ref, _reference(2 * T, [0], 6.0)),
    ]
    owners = {state: 'plant', ref: 'trajectory'}
    rec, missing = build_record(messages, ['x'], 3, T, [state, ref], owners)
    np.testing.assert_array_equal(rec['position'][:, 0], [1.0, 2.0, np.nan])
    np.testing.assert_array_equal(rec['reference'][:, 0], [np.nan, 5.0, 6.0])
    assert rec.foreign == {state: 3, ref: 4}
    assert missing == {state: 1, ref: 1}  # sample 0 has no reference point
    assert rec.gaps == {state: [(2, 2)], ref: [(0, 0)]}


def test_a_repeated_answer_to_a_reoffered_sample_is_one_override() -> None:
    from mill_analysis.bag_run import _feed_values
    from rclpy.serialization import serialize_message

    def override(stamp_ns: int, value: float) -> bytes:
        # every array filled: rclpy's serialize_message pads a message with an empty
        # float64 array beyond its CDR length (the wire does not), which no reader accepts
        msg = JointState(name=['override'], position=[value], velocity=[0.0], effort=[0.0])
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, 1_000_000_000)
        return serialize_message(msg)

    # step 0 answered three times (the plant re-offered it), then two instants
    sent = [(0, 1.1), (0, 1.1), (0, 1.1), (34_000_000, 1.4), (67_000_000, 1.4)]
    feed = [(10 + i, override(s, v)) for i, (s, v) in enumerate(sent)]
    notes: list[str] = []
    values = _feed_values('sensor_msgs/msg/JointState', feed, notes)
    assert values == [(10, 1.1), (13, 1.4), (14, 1.4)] and notes == []
