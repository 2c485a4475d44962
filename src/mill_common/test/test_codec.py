"""The hot-path codec agrees with rclpy.serialization, both ways, on generated messages, and
turns every malformed input into CodecError."""

from __future__ import annotations

import contextlib
import struct
from collections.abc import Callable, Sequence
from typing import Any

import pytest
from builtin_interfaces.msg import Duration, Time
from geometry_msgs.msg import WrenchStamped
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mill_common.codec import (
    CodecError,
    decode_joint_state,
    decode_joint_trajectory,
    decode_wrench_stamped,
    encode_clock,
    encode_joint_state,
    encode_joint_trajectory,
    encode_wrench_stamped,
)
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from mill_common import codec

EXAMPLES = settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])

# Anything a ROS string can hold: UTF-8 without NUL (CDR ends strings with it) or surrogates.
texts = st.text(
    st.characters(blacklist_categories=('Cs',), blacklist_characters='\x00'), max_size=12
)
doubles = st.floats(allow_nan=True, allow_infinity=True, width=64)
arrays = st.lists(doubles, max_size=5)
stamps_ns = st.integers(min_value=0, max_value=(2**31 - 1) * 1_000_000_000 + 999_999_999)
offsets_ns = st.integers(min_value=-(2**31) * 1_000_000_000, max_value=(2**31 - 1) * 10**9)


def bits(values: Sequence[float]) -> list[bytes]:
    """Floats compared bit for bit: NaN payloads, signed zeros."""
    return [struct.pack('<d', v) for v in values]


def split(ns: int) -> tuple[int, int]:
    return divmod(ns, 1_000_000_000)


def padding(encode: Callable[[], bytes]) -> set[int]:
    """Offsets of the padding bytes our encoder writes (where a different filler shows)."""
    zeros = encode()
    saved, layouts = codec._PAD, dict(codec._LAYOUTS)
    try:
        codec._PAD = tuple(b'\xaa' * len(p) for p in saved)
        codec._LAYOUTS.clear()  # the shapes written so far hold zero padding
        filled = encode()
    finally:
        codec._PAD = saved
        codec._LAYOUTS.clear()
        codec._LAYOUTS.update(layouts)
    assert len(zeros) == len(filled)
    return {i for i, (a, b) in enumerate(zip(zeros, filled, strict=True)) if a != b}


def same_bytes_but_padding(ours: bytes, reference: bytes, pads: set[int]) -> None:
    """Our bytes are the reference's but for padding. serialize_message returns a buffer of
    the RMW's estimated size, which may run on past the message: those bytes are not ours."""
    assert len(ours) <= len(reference)
    differ = [i for i, (a, b) in enumerate(zip(ours, reference, strict=False)) if a != b]
    assert set(differ) <= pads, (differ, ours.hex(), reference.hex())


# -- sensor_msgs/JointState ---------------------------------------------------------------------
@st.composite
def joint_states(draw: Any) -> tuple[int, str, list[str], list[float], list[float], list[float]]:
    return (
        draw(stamps_ns),
        draw(texts),
        draw(st.lists(texts, max_size=4)),
        draw(arrays),
        draw(arrays),
        draw(arrays),
    )


def ros_joint_state(ns: int, frame: str, names, pos, vel, eff) -> JointState:
    msg = JointState(name=list(names), position=list(pos), velocity=list(vel), effort=list(eff))
    msg.header.stamp = Time(sec=split(ns)[0], nanosec=split(ns)[1])
    msg.header.frame_id = frame
    return msg


@EXAMPLES
@given(joint_states())
def test_joint_state_bytes_equal_rclpy_serialization(values) -> None:
    ours = encode_joint_state(*values)
    reference = serialize_message(ros_joint_state(*values))
    same_bytes_but_padding(ours, reference, padding(lambda: encode_joint_state(*values)))


@EXAMPLES
@given(joint_states())
def test_joint_state_round_trips_through_rclpy(values) -> None:
    ns, frame, names, pos, vel, eff = values
    back = deserialize_message(encode_joint_state(*values), JointState)
    assert (back.header.stamp.sec, back.header.stamp.nanosec) == split(ns)
    assert back.header.frame_id == frame
    assert list(back.name) == names
    assert bits(back.position) == bits(pos)
    assert bits(back.velocity) == bits(vel)
    assert bits(back.effort) == bits(eff)

    got = decode_joint_state(serialize_message(ros_joint_state(*values)))
    assert (got.header.stamp.sec, got.header.stamp.nanosec) == split(ns)
    assert got.header.frame_id == frame
    assert got.name == names
    assert bits(got.position) == bits(pos)
    assert bits(got.velocity) == bits(vel)
    assert bits(got.effort) == bits(eff)


@EXAMPLES
@given(
    st.integers(-(2**31), 2**31 - 1), st.integers(0, 2**32 - 1), texts, st.lists(texts, max_size=3)
)
def test_joint_state_decodes_any_stamp_rclpy_writes(sec, nanosec, frame, names) -> None:
    msg = JointState(name=names)
    msg.header.stamp = Time(sec=sec, nanosec=nanosec)
    msg.header.frame_id = frame
    got = decode_joint_state(serialize_message(msg))
    assert (got.header.stamp.sec, got.header.stamp.nanosec) == (sec, nanosec)
    assert got.name == names
    assert got.position == got.velocity == got.effort == ()


def test_big_endian_joint_state_is_read() -> None:
    # Header (0x00 0x00: big endian), stamp 3 s 7 ns, frame 'p', one name 'x', one position.
    data = (
        b'\x00\x00\x00\x00'
        + struct.pack('>iI', 3, 7)
        + struct.pack('>I', 2)
        + b'p\x00\x00\x00'
        + struct.pack('>I', 1)
        + struct.pack('>I', 2)
        + b'x\x00\x00\x00'
        + struct.pack('>I', 1)  # offset 32: the float64 at 36 is aligned (32 after the header)
        + struct.pack('>d', 0.25)
        + struct.pack('>I', 0)
        + struct.pack('>I', 0)
    )
    got = decode_joint_state(data)
    assert (got.header.stamp.sec, got.header.stamp.nanosec, got.header.frame_id) == (3, 7, 'p')
    assert (got.name, got.position, got.velocity, got.effort) == (['x'], (0.25,), (), ())


# -- trajectory_msgs/JointTrajectory ------------------------------------------------------------
points = st.lists(st.tuples(arrays, arrays, arrays, arrays, offsets_ns), max_size=4)


def ros_trajectory(ns: int, frame: str, names, pts) -> JointTrajectory:
    msg = JointTrajectory(joint_names=list(names))
    msg.header.stamp = Time(sec=split(ns)[0], nanosec=split(ns)[1])
    msg.header.frame_id = frame
    for pos, vel, acc, eff, offset in pts:
        sec, nanosec = split(offset)
        msg.points.append(
            JointTrajectoryPoint(
                positions=list(pos),
                velocities=list(vel),
                accelerations=list(acc),
                effort=list(eff),
                time_from_start=Duration(sec=sec, nanosec=nanosec),
            )
        )
    return msg


@EXAMPLES
@given(stamps_ns, texts, st.lists(texts, max_size=4), points)
def test_joint_trajectory_agrees_with_rclpy_both_ways(ns, frame, names, pts) -> None:
    ours = encode_joint_trajectory(ns, frame, names, pts)
    reference = serialize_message(ros_trajectory(ns, frame, names, pts))
    pads = padding(lambda: encode_joint_trajectory(ns, frame, names, pts))
    same_bytes_but_padding(ours, reference, pads)

    back = deserialize_message(ours, JointTrajectory)
    assert list(back.joint_names) == names and back.header.frame_id == frame
    got = decode_joint_trajectory(reference)
    assert (got.header.stamp.sec, got.header.stamp.nanosec) == split(ns)
    assert got.joint_names == names and got.header.frame_id == frame
    assert len(back.points) == len(got.points) == len(pts)
    for theirs, mine, (pos, vel, acc, eff, offset) in zip(
        back.points, got.points, pts, strict=True
    ):
        for field, values in (
            ('positions', pos),
            ('velocities', vel),
            ('accelerations', acc),
            ('effort', eff),
        ):
            assert bits(getattr(theirs, field)) == bits(values)
            assert bits(getattr(mine, field)) == bits(values)
        for t in (theirs.time_from_start, mine.time_from_start):
            assert (t.sec, t.nanosec) == split(offset)


# -- geometry_msgs/WrenchStamped ----------------------------------------------------------------
@EXAMPLES
@given(stamps_ns, texts, st.tuples(doubles, doubles, doubles), st.tuples(doubles, doubles, doubles))
def test_wrench_stamped_agrees_with_rclpy_both_ways(ns, frame, force, torque) -> None:
    ours = encode_wrench_stamped(ns, frame, force, torque)
    msg = WrenchStamped()
    msg.header.stamp = Time(sec=split(ns)[0], nanosec=split(ns)[1])
    msg.header.frame_id = frame
    msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z = force
    msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z = torque
    reference = serialize_message(msg)
    pads = padding(lambda: encode_wrench_stamped(ns, frame, force, torque))
    same_bytes_but_padding(ours, reference, pads)
    got = decode_wrench_stamped(reference)
    assert got.header.frame_id == frame
    w = got.wrench
    assert bits((w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z)) == bits(
        (*force, *torque)
    )
    back = deserialize_message(ours, WrenchStamped)
    assert bits((back.wrench.force.x, back.wrench.torque.z)) == bits((force[0], torque[2]))


# -- rosgraph_msgs/Clock --------------------------------------------------------------------------
@EXAMPLES
@given(stamps_ns)
def test_clock_equals_rclpy_serialization(ns) -> None:
    from rosgraph_msgs.msg import Clock

    sec, nanosec = split(ns)
    assert encode_clock(ns) == serialize_message(Clock(clock=Time(sec=sec, nanosec=nanosec)))
    back = deserialize_message(encode_clock(ns), Clock)
    assert (back.clock.sec, back.clock.nanosec) == (sec, nanosec)


def test_a_clock_out_of_range_is_refused() -> None:
    with pytest.raises(codec.CodecError, match='does not fit'):
        encode_clock(2**31 * 1_000_000_000)


# -- malformed input ----------------------------------------------------------------------------
DECODERS = (decode_joint_state, decode_joint_trajectory, decode_wrench_stamped)


def valid_messages() -> list[tuple[Callable[[bytes], Any], bytes]]:
    return [
        (decode_joint_state, encode_joint_state(5, 'plant', ['x', 'y'], [1.0, 2.0], [], [3.0])),
        (
            decode_joint_trajectory,
            encode_joint_trajectory(
                7, 'trajectory', ['x', 'y', 'z'], [((1.0, 2.0, 3.0), (0.0,) * 3, (), (), 1000)]
            ),
        ),
        (decode_wrench_stamped, encode_wrench_stamped(9, 'tool', (1.0, 2.0, 3.0))),
    ]


@pytest.mark.parametrize(('decode', 'data'), valid_messages())
def test_every_truncation_is_refused(decode, data) -> None:
    decode(data)
    for n in range(len(data)):
        with pytest.raises(CodecError):
            decode(data[:n])


def test_what_is_wrong_is_said() -> None:
    good = encode_joint_state(5, 'plant', ['x'], [1.0])
    cases = {
        b'\x00\x01': 'fewer than the 4',
        b'\x00\x03\x00\x00' + good[4:]: 'not plain CDR',
        good[:12] + struct.pack('<I', 10**6) + good[16:]: 'does not fit',
        good[:21] + b'!' + good[22:]: 'does not end with NUL',
        good[:16] + b'\xff\xfe' + good[18:]: 'not UTF-8',
        good[:24] + struct.pack('<I', 10**8) + good[28:]: 'strings at offset',
    }
    for data, reason in cases.items():
        with pytest.raises(CodecError, match=reason):
            decode_joint_state(data)


@settings(max_examples=500, deadline=None)
@given(st.binary(max_size=200))
def test_random_bytes_decode_or_raise_codec_error(data) -> None:
    for decode in DECODERS:
        with contextlib.suppress(CodecError):
            decode(data)


@settings(max_examples=300, deadline=None)
@given(st.data())
def test_corrupted_messages_decode_or_raise_codec_error(data) -> None:
    decode, good = data.draw(st.sampled_from(valid_messages()))
    raw = bytearray(good)
    for _ in range(data.draw(st.integers(1, 4))):
        raw[data.draw(st.integers(0, len(raw) - 1))] = data.draw(st.integers(0, 255))
    with contextlib.suppress(CodecError):
        decode(bytes(raw))


def test_a_whole_message_may_end_in_its_padding_only() -> None:
    # rclpy ignores bytes after a message; a bag's message is its bytes (rosbags refuses more)
    good = encode_joint_state(5, 'plant', ['x'], [1.0])
    for extra in (b'', b'\x00' * 3, b'\x00' * 4):
        assert decode_joint_state(good + extra).position == (1.0,)
    assert decode_joint_state(good + b'\x00' * 3, whole=True).position == (1.0,)
    with pytest.raises(CodecError, match='4 bytes after the JointState'):
        decode_joint_state(good + b'\x00' * 4, whole=True)


def test_a_nul_in_a_string_cannot_be_encoded() -> None:
    with pytest.raises(CodecError, match='NUL'):
        encode_joint_state(0, 'pl\x00ant', ['x'])


def test_a_joint_state_stamp_out_of_range_is_refused_also_for_a_known_shape() -> None:
    encode_joint_state(0, 'plant', ['x'], [1.0])  # the shape is known from here on
    for ns in (2**31 * 1_000_000_000, -(2**31) * 1_000_000_000 - 1):
        with pytest.raises(CodecError, match='does not fit'):
            encode_joint_state(ns, 'plant', ['x'], [1.0])


def test_joint_states_of_more_shapes_than_are_kept_are_written_alike() -> None:
    # Past the kept layouts each message is laid out anew: the same bytes either way.
    for i in range(codec._MAX_LAYOUTS + 20):
        sender, names = f'node_{i}', [f'j{k}' for k in range(i % 4)]
        values = [float(k) for k in range(i % 3)]
        data = encode_joint_state(i, sender, names, values, (), values)
        assert encode_joint_state(i, sender, names, values, (), values) == data
        back = decode_joint_state(data)
        assert (back.header.frame_id, back.name, list(back.position)) == (sender, names, values)
        assert (back.header.stamp.sec, back.header.stamp.nanosec) == (0, i)


def _fields(msg: Any) -> tuple[Any, ...]:
    return (
        msg.header.stamp.sec,
        msg.header.stamp.nanosec,
        msg.header.frame_id,
        msg.name,
        bits(msg.position),
        bits(msg.velocity),
        bits(msg.effort),
    )


def _long_way(data: bytes) -> Any:
    kept = dict(codec._READ_LAYOUTS)
    codec._READ_LAYOUTS.clear()
    try:
        return decode_joint_state(data)
    finally:
        codec._READ_LAYOUTS.clear()
        codec._READ_LAYOUTS.update(kept)


@settings(max_examples=300, deadline=None)
@given(joint_states(), st.data())
def test_a_known_shape_is_read_as_the_long_way_reads_it(values, data) -> None:
    good = encode_joint_state(*values)
    decode_joint_state(good)  # its shape is known from here on (if it can be)
    raw = bytearray(good)
    for _ in range(data.draw(st.integers(0, 3))):  # a stamp, a value, a count, a padding byte
        raw[data.draw(st.integers(0, len(raw) - 1))] = data.draw(st.integers(0, 255))
    try:
        expected = _fields(_long_way(bytes(raw)))
    except CodecError:
        with pytest.raises(CodecError):
            decode_joint_state(bytes(raw))
        return
    assert _fields(decode_joint_state(bytes(raw))) == expected
