"""CDR without a typestore: a message's leading stamp, and a fast sensor_msgs/JointState reader.

Both read the bytes as ROS 2 RMWs serialize them (XCDR1, a 4-byte encapsulation
header first). `cdr_stamp_ns` is what a recorder on sim time stamps messages with;
`joint_state_cdr` decodes sensor_msgs/JointState, most of the messages of a
joint-level control loop, 4x faster than rosbags (`mill_bag.types.decode` uses it
and falls back to rosbags for anything it does not accept).
"""

from __future__ import annotations

import operator
import struct
from dataclasses import dataclass
from typing import Any


def cdr_stamp_ns(data: bytes) -> int | None:
    """The leading builtin_interfaces/Time of a CDR message (a Header's stamp, Clock.clock) [ns].

    CDR starts with a 4-byte encapsulation header (00 00 big endian, 00 01 little
    endian); the stamp (int32 sec, uint32 nanosec) follows at offset 4.
    """
    if len(data) < 12 or data[0] != 0 or data[1] > 1:
        return None
    sec, nanosec = struct.unpack_from('<iI' if data[1] else '>iI', data, 4)
    return sec * 1_000_000_000 + nanosec


class _Stamp:
    __slots__ = ('nanosec', 'sec')

    def __init__(self, sec: int, nanosec: int) -> None:
        self.sec, self.nanosec = sec, nanosec


class _Header:
    __slots__ = ('frame_id', 'stamp')

    def __init__(self, stamp: _Stamp, frame_id: str) -> None:
        self.stamp, self.frame_id = stamp, frame_id


class JointStateData:
    """sensor_msgs/JointState as read by joint_state_cdr; float arrays are tuples."""

    __slots__ = ('effort', 'header', 'name', 'position', 'velocity')

    def __init__(
        self,
        header: _Header,
        name: list[str],
        position: tuple[float, ...],
        velocity: tuple[float, ...],
        effort: tuple[float, ...],
    ) -> None:
        self.header, self.name = header, name
        self.position, self.velocity, self.effort = position, velocity, effort


_U32 = struct.Struct('<I')
_STAMP = struct.Struct('<iII')


@dataclass(frozen=True)
class _Layout:
    """Where the values of one JointState shape sit: all messages of a topic share it."""

    fixed: Any  # operator.itemgetter of the slices that every such message repeats
    expected: tuple[bytes, ...]  # ... and what they hold
    values: struct.Struct  # stamp and all float64s from offset 4, padding skipped
    counts: tuple[int, int, int]
    frame_id: str
    names: tuple[str, ...]


_LAYOUTS: dict[int, list[_Layout]] = {}


def joint_state_cdr(data: bytes) -> JointStateData | None:
    """sensor_msgs/JointState from little-endian CDR (XCDR1, as ROS 2 RMWs write it).

    Layout after the 4-byte encapsulation header (offsets aligned relative to its
    end): stamp int32 sec, uint32 nanosec; frame_id (uint32 length with the NUL,
    bytes); name (uint32 count, strings); position, velocity, effort (uint32
    count, float64s aligned to 8). The first message of a shape is parsed field by
    field; later ones with the same length and the same non-value bytes (lengths,
    counts, names) are read with one struct. Returns None for anything else (big
    endian, inconsistent lengths), which `types.decode` hands to rosbags. Checked against
    rosbags and mcap_ros2 on every JointState of a recorded run (test_recording).
    """
    for layout in _LAYOUTS.get(len(data), ()):
        if layout.fixed(data) == layout.expected:
            v = layout.values.unpack_from(data, 4)
            n1, n2, _ = layout.counts
            return JointStateData(
                _Header(_Stamp(v[0], v[1]), layout.frame_id),
                list(layout.names),
                v[2 : 2 + n1],
                v[2 + n1 : 2 + n1 + n2],
                v[2 + n1 + n2 :],
            )
    if len(data) < 16 or data[0] != 0 or data[1] != 1:
        return None
    try:
        sec, nanosec, length = _STAMP.unpack_from(data, 4)
        o = 16 + length
        frame_id = data[16 : o - 1].decode()
        o += -(o - 4) % 4
        (count,) = _U32.unpack_from(data, o)
        o += 4
        names = []
        for _ in range(count):
            o += -(o - 4) % 4
            (length,) = _U32.unpack_from(data, o)
            names.append(data[o + 4 : o + 3 + length].decode())
            o += 4 + length
        arrays = []
        regions = [(4, 12)]  # value bytes: the stamp, then each float64 array
        for _ in range(3):
            o += -(o - 4) % 4
            (count,) = _U32.unpack_from(data, o)
            o += 4
            if count:
                o += -(o - 4) % 8
                arrays.append(struct.unpack_from(f'<{count}d', data, o))
                regions.append((o, o + 8 * count))
                o += 8 * count
            else:
                arrays.append(())
    except (struct.error, UnicodeDecodeError):
        return None
    if not len(data) - 3 <= o <= len(data):  # at most the final alignment padding is left
        return None
    fixed = [slice(0, 4)]
    fmt = '<iI'
    ends = [*regions[1:], (len(data), len(data))]
    for (_, end), (start, stop) in zip(regions, ends, strict=True):
        fixed.append(slice(end, start))
        if stop > start:
            fmt += f'{start - end}x{(stop - start) // 8}d'
    getter = operator.itemgetter(*fixed)
    layout = _Layout(
        getter,
        getter(data),
        struct.Struct(fmt),
        (len(arrays[0]), len(arrays[1]), len(arrays[2])),  # position, velocity, effort
        frame_id,
        tuple(names),
    )
    _LAYOUTS.setdefault(len(data), []).append(layout)
    return JointStateData(_Header(_Stamp(sec, nanosec), frame_id), names, *arrays)
