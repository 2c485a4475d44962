"""The record takes what the nodes take (mill_analysis.node_intake): spoofed far-ahead states
with the owner's name, foreign senders and stamps in the past are left out, counted with their
reason; a step's messages that reach the listener out of order are not; every topic, the
commands too, counts its missing samples."""

from __future__ import annotations

import math

import numpy as np
from builtin_interfaces.msg import Duration
from mill_analysis.lockstep_record import build_record
from mill_analysis.node_intake import Drops, drop_lines
from mill_common.checks import Rejected
from mill_common.timebase import time_ns
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from mill_analysis import bag_meta
from mill_common import topics

T = 1_000_000  # 1 ms [ns]
N = 40
STATE, ESTIMATE, COMMAND = topics.state('x'), topics.estimate('x'), topics.joint_command('x')
REF = topics.REFERENCE
OWNERS = {STATE: 'plant', ESTIMATE: 'x_observer', COMMAND: 'x_controller', REF: 'trajectory'}
LISTENED = [STATE, ESTIMATE, COMMAND, REF]


def joint_state(topic: str, k: int, value: float, sender: str | None = None) -> JointState:
    msg = JointState(name=['x'])
    if topic == STATE:
        msg.position = [value]
    elif topic == ESTIMATE:
        msg.position, msg.velocity, msg.effort = [value], [value], [value]
    else:
        msg.effort = [value]
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(k * T, 1_000_000_000)
    msg.header.frame_id = OWNERS[topic] if sender is None else sender
    return msg


def reference(k: int) -> JointTrajectory:
    msg = JointTrajectory(joint_names=['x'])
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(k * T, 1_000_000_000)
    msg.header.frame_id = 'trajectory'
    for j in range(20):
        d = Duration(sec=0, nanosec=j * T)
        msg.points.append(JointTrajectoryPoint(positions=[1e-3 * (k + j)], time_from_start=d))
    return msg


def lockstep(skip: dict[str, range] | None = None, n: int = N) -> list[tuple[str, object]]:
    """What a listener gets of a lockstep job on axis x, in order: per step the state, the
    estimate, the command (the value k each), and the reference every 10 steps."""
    out: list[tuple[str, object]] = []
    for k in range(n):
        if k % 10 == 0:
            out.append((REF, reference(k)))
        for topic in (STATE, ESTIMATE, COMMAND):
            if k not in (skip or {}).get(topic, ()):
                out.append((topic, joint_state(topic, k, float(k))))
    return out


def record(messages):
    return build_record(messages, ['x'], N, T, LISTENED, OWNERS)


def after(messages: list[tuple[str, object]], topic: str, k: int) -> int:
    """The index just after the message of `topic` for step k."""
    return 1 + next(i for i, (t, m) in enumerate(messages) if t == topic and _k(m) == k)


def test_a_genuine_run_is_taken_whole() -> None:
    rec, missing = record(lockstep())
    assert missing == dict.fromkeys(LISTENED, 0) and rec.foreign == {} and rec.gaps == {}
    np.testing.assert_array_equal(rec['position'][:, 0], np.arange(N))
    np.testing.assert_array_equal(rec['torque'][:, 0], np.arange(N))


def test_far_ahead_states_with_the_owners_name_are_left_out_with_their_reason() -> None:
    # The attack: ten states stamped 0.3 s to 10 s ahead, named as the plant's, sent while
    # the job is at step 5; each names a sample of the job (N is longer here).
    n = 10_001
    spoofs = [300, 500, 1000, 2000, 3000, 4000, 5000, 7000, 9000, 10_000]
    messages = lockstep(n=n)
    at = after(messages, STATE, 5)
    messages[at:at] = [(STATE, joint_state(STATE, k, -1.0)) for k in spoofs]
    rec, missing = build_record(messages, ['x'], n, T, LISTENED, OWNERS)
    assert missing == dict.fromkeys(LISTENED, 0)
    assert rec.foreign == {STATE: 10}
    reasons = rec.drops.reasons()[STATE]
    assert [count for count, _ in reasons] == [10]
    assert reasons[0][1] == 'stamp 0.300000 s is ahead of the plant (newest state 0.005000 s)'
    # the genuine states of those samples, which came later, are in the record
    np.testing.assert_array_equal(rec['position'][:, 0], np.arange(n))


def _k(msg) -> int:
    return time_ns(msg.header.stamp) // T


def test_foreign_senders_and_stamps_in_the_past_are_left_out() -> None:
    messages = lockstep()
    messages.insert(after(messages, STATE, 2), (COMMAND, joint_state(COMMAND, 2, 99.0, 'intruder')))
    # the owner's name, a step it has sent: the same step again (the first counts), an older one
    messages.insert(after(messages, COMMAND, 3), (STATE, joint_state(STATE, 3, 99.0)))
    messages.insert(after(messages, COMMAND, 4), (ESTIMATE, joint_state(ESTIMATE, 1, 99.0)))
    rec, missing = record(messages)
    assert missing == dict.fromkeys(LISTENED, 0)
    assert rec.foreign == {COMMAND: 1, ESTIMATE: 1}
    for name in ('position', 'estimate_velocity', 'torque'):
        np.testing.assert_array_equal(rec[name][:, 0], np.arange(N), err_msg=name)
    lines = drop_lines(rec.drops.reasons())
    assert lines == [
        f"ERROR: {COMMAND}: 1 messages left out of the record: 1 like \"sent by 'intruder', "
        "not by its owner 'x_controller'\"",
        f'ERROR: {ESTIMATE}: 1 messages left out of the record: 1 like "stamp 0.001000 s is '
        'in the past (newest 0.004000 s)"',
    ]


def test_a_steps_messages_out_of_order_at_the_listener_are_taken() -> None:
    # The listener gets the state topic late (its writer's messages held up), the estimates
    # and commands of the steps meanwhile: each proves the plant got to its step.
    messages = lockstep()
    late = [m for m in messages if m[0] == STATE and 10 <= _k(m[1]) < 30]
    rest = [m for m in messages if m not in late]
    at = next(i for i, m in enumerate(rest) if m[0] == STATE and _k(m[1]) == 30)
    rec, missing = record(rest[:at] + late + rest[at:])
    assert rec.foreign == {} and missing == dict.fromkeys(LISTENED, 0)
    np.testing.assert_array_equal(rec['position'][:, 0], np.arange(N))


def test_missing_commands_are_counted_and_named() -> None:
    rec, missing = record(lockstep(skip={COMMAND: range(0, 17)}))
    assert missing == {STATE: 0, ESTIMATE: 0, COMMAND: 17, REF: 0}
    assert rec.gaps == {COMMAND: [(0, 16)]}
    assert bag_meta.loss_lines({COMMAND: 17}, rec.gaps) == [
        f'WARNING: {COMMAND}: samples missing in the record: 17 (k = 0–16)'
    ]
    assert math.isnan(rec['torque'][16, 0]) and rec['torque'][17, 0] == 17.0


def test_missing_ranges_and_their_text() -> None:
    assert bag_meta.missing_ranges({1, 2, 5}, 8) == [(0, 0), (3, 4), (6, 7)]
    assert bag_meta.missing_ranges(set(range(4)), 4) == []
    many = [(k, k) for k in range(0, 20, 2)]
    assert bag_meta.format_ranges(many) == 'k = 0, 2, 4, 6, 8, 10 and 4 more runs'


def test_drops_count_reasons_that_differ_only_in_numbers_together() -> None:
    drops = Drops()
    for k in (3, 4, 5):
        drops.add(STATE, Rejected(f'stamp {k}.0 s is in the past (newest 9.0 s)'))
    drops.add(STATE, Rejected("sent by 'a', not by its owner 'plant'"))
    assert drops.per_topic() == {STATE: 4}
    assert drops.reasons() == {
        STATE: [
            (3, 'stamp 3.0 s is in the past (newest 9.0 s)'),
            (1, "sent by 'a', not by its owner 'plant'"),
        ]
    }
