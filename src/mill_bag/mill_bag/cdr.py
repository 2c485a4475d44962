"""CDR without a typestore: a message's leading stamp, and a fast sensor_msgs/JointState reader.

Both read the bytes as ROS 2 RMWs serialize them (XCDR1, a 4-byte encapsulation
header first). `cdr_stamp_ns` is what a recorder on sim time stamps messages with;
`joint_state_cdr` decodes sensor_msgs/JointState, most of the messages of a
joint-level control loop, 4x faster than rosbags (`mill_bag.types.decode` uses it
and falls back to rosbags for anything it does not accept). The decoding is the
nodes' own (`mill_common.codec`, ROS-free and generic: no mill knowledge).
"""

from __future__ import annotations

import struct

from mill_common.codec import CodecError, JointStateData, decode_joint_state
from mill_common.timebase import stamp_ns


def cdr_stamp_ns(data: bytes) -> int | None:
    """The leading builtin_interfaces/Time of a CDR message (a Header's stamp, Clock.clock) [ns].

    CDR starts with a 4-byte encapsulation header (00 00 big endian, 00 01 little
    endian); the stamp (int32 sec, uint32 nanosec) follows at offset 4.
    """
    if len(data) < 12 or data[0] != 0 or data[1] > 1:
        return None
    return stamp_ns(*struct.unpack_from('<iI' if data[1] else '>iI', data, 4))


def joint_state_cdr(data: bytes) -> JointStateData | None:
    """sensor_msgs/JointState from little-endian CDR (XCDR1, as ROS 2 RMWs write it).

    `mill_common.codec.decode_joint_state`, the nodes' reader (a message of a shape seen
    before in one struct call), on a bag's message: the bytes must be the whole message (at
    most the final alignment padding after it). Returns None for anything else (big
    endian, inconsistent lengths), which `types.decode` hands to rosbags. Checked against
    rosbags and mcap_ros2 on every JointState of a recorded run (test_recording).
    """
    if data[1:2] != b'\x01':  # big endian (or no CDR): rosbags reads it
        return None
    try:
        return decode_joint_state(data, whole=True)
    except CodecError:
        return None
