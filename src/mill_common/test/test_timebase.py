"""A stamp in nanoseconds, the same from its two fields and from each kind of message object."""

from __future__ import annotations

from builtin_interfaces.msg import Duration, Time
from hypothesis import given
from hypothesis import strategies as st
from mill_common.codec import decode_joint_state, encode_joint_state
from mill_common.ros import from_duration, from_stamp, to_stamp
from mill_common.timebase import stamp_ns, time_ns

stamps_ns = st.integers(min_value=0, max_value=(2**31 - 1) * 1_000_000_000 + 999_999_999)


@given(stamps_ns)
def test_a_stamp_in_ns_from_its_fields_and_from_messages(ns: int) -> None:
    sec, nanosec = divmod(ns, 1_000_000_000)
    assert stamp_ns(sec, nanosec) == ns
    assert time_ns(Time(sec=sec, nanosec=nanosec)) == ns
    assert time_ns(Duration(sec=sec, nanosec=nanosec)) == ns
    assert time_ns(decode_joint_state(encode_joint_state(ns, 'p', ['x'])).header.stamp) == ns
    assert from_stamp(to_stamp(ns)) == ns


def test_a_negative_duration_in_ns() -> None:
    assert stamp_ns(-1, 999_999_999) == -1
    assert from_duration(Duration(sec=-2, nanosec=500_000_000)) == -1_500_000_000
