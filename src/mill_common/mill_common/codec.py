"""CDR bytes of the hot-path messages, written and read without rclpy message objects. ROS-free.

The nodes of a lockstep step exchange about thirty messages, nearly all of them
sensor_msgs/JointState, and every 10 ms one trajectory_msgs/JointTrajectory. Building an
rclpy message object, converting it to C and serializing it costs about 70 µs of CPU in
Python, and the way back (deserializing and building the object) more (docs/performance.md).
This module writes those messages' serialized form directly from the values, and reads the
bytes into light objects with the fields the nodes use, in a few µs. The nodes publish the
bytes (`Publisher.publish(bytes)`) and subscribe with `raw=True`; on the wire nothing changes,
so a node or a hardware driver that uses ordinary messages talks to them as before.

Format: the serialized form of the ROS 2 RMWs, XCDR1 (plain CDR). A 4-byte encapsulation
header (0x00 0x01: little endian, 0x00 0x00: big endian; two option bytes), then the fields
in declaration order, each primitive aligned to its size relative to the end of the header.
A string is a uint32 length that counts a final NUL, the UTF-8 bytes and the NUL; a sequence
is a uint32 count and its elements. We write little endian with zero padding; `rclpy.
serialization` is the reference (the tests check both directions on many generated messages;
Fast DDS leaves its padding bytes unset, so only the non-padding bytes can be compared).

Reading checks everything a malformed message can get wrong — encapsulation, lengths and
counts beyond the end, a string without its NUL or not UTF-8 — and raises CodecError with one
line saying what; nothing else escapes. Bytes after the message are ignored, as rclpy ignores
them: `serialize_message` itself returns a buffer of the RMW's estimated size, which can be
longer than the message.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence

HEADER_LE = b'\x00\x01\x00\x00'  # CDR_LE, no options
_PAD = tuple(b'\x00' * n for n in range(8))  # to the next boundary: 0 to 7 zero bytes


class CodecError(ValueError):
    """Bytes that are not a message of the expected type; str() says why in one line."""


# -- the objects a decoder returns: the fields the nodes read, with the messages' names ------
class Time:
    """builtin_interfaces/Time (and Duration: the same two fields)."""

    __slots__ = ('nanosec', 'sec')

    def __init__(self, sec: int = 0, nanosec: int = 0) -> None:
        self.sec, self.nanosec = sec, nanosec


class Header:
    __slots__ = ('frame_id', 'stamp')

    def __init__(self, stamp: Time, frame_id: str) -> None:
        self.stamp, self.frame_id = stamp, frame_id


class JointStateData:
    """sensor_msgs/JointState; the float arrays are tuples."""

    __slots__ = ('effort', 'header', 'name', 'position', 'velocity')

    def __init__(
        self,
        header: Header,
        name: list[str],
        position: tuple[float, ...],
        velocity: tuple[float, ...],
        effort: tuple[float, ...],
    ) -> None:
        self.header, self.name = header, name
        self.position, self.velocity, self.effort = position, velocity, effort


class TrajectoryPointData:
    """trajectory_msgs/JointTrajectoryPoint."""

    __slots__ = ('accelerations', 'effort', 'positions', 'time_from_start', 'velocities')

    def __init__(
        self,
        positions: tuple[float, ...],
        velocities: tuple[float, ...],
        accelerations: tuple[float, ...],
        effort: tuple[float, ...],
        time_from_start: Time,
    ) -> None:
        self.positions, self.velocities, self.accelerations = positions, velocities, accelerations
        self.effort, self.time_from_start = effort, time_from_start


class JointTrajectoryData:
    """trajectory_msgs/JointTrajectory."""

    __slots__ = ('header', 'joint_names', 'points')

    def __init__(
        self, header: Header, joint_names: list[str], points: list[TrajectoryPointData]
    ) -> None:
        self.header, self.joint_names, self.points = header, joint_names, points


class Vector3:
    __slots__ = ('x', 'y', 'z')

    def __init__(self, x: float, y: float, z: float) -> None:
        self.x, self.y, self.z = x, y, z


class Wrench:
    __slots__ = ('force', 'torque')

    def __init__(self, force: Vector3, torque: Vector3) -> None:
        self.force, self.torque = force, torque


class WrenchStampedData:
    """geometry_msgs/WrenchStamped."""

    __slots__ = ('header', 'wrench')

    def __init__(self, header: Header, wrench: Wrench) -> None:
        self.header, self.wrench = header, wrench


# -- writing ----------------------------------------------------------------------------------
_U32 = struct.Struct('<I')
_STAMP = struct.Struct('<iI')
_DOUBLES: dict[int, struct.Struct] = {}


_CACHED = 64  # the structs of short arrays are kept; a count read off the wire is not


def _doubles_struct(n: int, order: str = '<') -> struct.Struct:
    key = n if order == '<' else -n - 1
    s = _DOUBLES.get(key)
    if s is None:
        s = struct.Struct(f'{order}{n}d')
        if n <= _CACHED:
            _DOUBLES[key] = s
    return s


def _put_string(buf: bytearray, text: str) -> None:
    data = text.encode()
    if b'\x00' in data:
        raise CodecError(f'string {text!r} holds a NUL, which CDR cannot carry')
    buf += _PAD[-(len(buf) - 4) % 4]
    buf += _U32.pack(len(data) + 1)
    buf += data
    buf += b'\x00'


def _put_strings(buf: bytearray, texts: Sequence[str]) -> None:
    buf += _PAD[-(len(buf) - 4) % 4]
    buf += _U32.pack(len(texts))
    for text in texts:
        _put_string(buf, text)


def _put_doubles(buf: bytearray, values: Sequence[float]) -> None:
    buf += _PAD[-(len(buf) - 4) % 4]
    n = len(values)
    buf += _U32.pack(n)
    if n:
        buf += _PAD[-(len(buf) - 4) % 8]
        buf += _doubles_struct(n).pack(*values)


def _put_header(buf: bytearray, ns: int, frame_id: str) -> None:
    sec, nanosec = divmod(ns, 1_000_000_000)
    try:
        buf += _STAMP.pack(sec, nanosec)
    except struct.error:
        raise CodecError(f'stamp {ns} ns does not fit builtin_interfaces/Time') from None
    _put_string(buf, frame_id)


class _JointStateLayout:
    """The bytes of every JointState of one shape (sender, joint names, array lengths) but
    the stamp and the values: one struct writes, or reads, a message of that shape in one
    call. Written with zero padding; read only where every byte but the stamp's and the
    values' is the same, padding included (anything else takes the long way)."""

    __slots__ = ('frame_id', 'names', 'pack', 'segments', 'size', 'slices', 'unpack_from')

    def __init__(self, frame_id: str, name: tuple[str, ...], counts: tuple[int, ...]) -> None:
        buf = bytearray(HEADER_LE)
        buf += bytes(_STAMP.size)
        fmt, segments, start = f'<4s{_STAMP.format[1:]}', [], len(buf)
        _put_string(buf, frame_id)  # CodecError for a NUL, as on the long way
        _put_strings(buf, name)
        for n in counts:  # each array: the constant bytes before its values, then the values
            buf += _PAD[-(len(buf) - 4) % 4]
            buf += _U32.pack(n)
            if n:
                buf += _PAD[-(len(buf) - 4) % 8]
            segments.append(bytes(buf[start:]))
            fmt += f'{len(segments[-1])}s{n}d'
            buf += bytes(8 * n)
            start = len(buf)
        self.frame_id, self.names = frame_id, list(name)
        self.segments = tuple(segments)
        layout = struct.Struct(fmt)
        self.pack, self.unpack_from, self.size = layout.pack, layout.unpack_from, layout.size
        # where the constant segments and the three arrays sit in what unpack_from returns
        n1, n2, n3 = counts
        self.slices = (
            (3, 4 + n1, 5 + n1 + n2),
            (
                slice(4, 4 + n1),
                slice(5 + n1, 5 + n1 + n2),
                slice(6 + n1 + n2, 6 + n1 + n2 + n3),
            ),
        )

    def read(self, data: bytes) -> JointStateData | None:
        """The message, if `data` is one of this shape with zero padding; else None."""
        v = self.unpack_from(data)
        (a, b, c), (pos, vel, eff) = self.slices
        if v[0] != HEADER_LE or (v[a], v[b], v[c]) != self.segments:
            return None
        header = Header(Time(v[1], v[2]), self.frame_id)
        return JointStateData(header, list(self.names), v[pos], v[vel], v[eff])


_LAYOUTS: dict[tuple[object, ...], _JointStateLayout] = {}
_MAX_LAYOUTS = 256  # a node sends a few shapes; odd ones beyond these are written each time
_INT32 = 2**31  # builtin_interfaces/Time.sec is an int32


def encode_joint_state(
    ns: int,
    frame_id: str,
    name: Sequence[str],
    position: Sequence[float] = (),
    velocity: Sequence[float] = (),
    effort: Sequence[float] = (),
) -> bytes:
    """sensor_msgs/JointState stamped `ns` [ns since the epoch of its clock]."""
    key = (frame_id, *name, None, len(position), len(velocity), len(effort))
    layout = _LAYOUTS.get(key)
    if layout is None:
        layout = _JointStateLayout(frame_id, tuple(name), key[-3:])  # type: ignore[arg-type]
        if len(_LAYOUTS) < _MAX_LAYOUTS:
            _LAYOUTS[key] = layout
    sec, nanosec = divmod(ns, 1_000_000_000)
    if not -_INT32 <= sec < _INT32:
        raise CodecError(f'stamp {ns} ns does not fit builtin_interfaces/Time')
    a, b, c = layout.segments
    return layout.pack(HEADER_LE, sec, nanosec, a, *position, b, *velocity, c, *effort)


def encode_joint_trajectory(
    ns: int,
    frame_id: str,
    joint_names: Sequence[str],
    points: Sequence[
        tuple[Sequence[float], Sequence[float], Sequence[float], Sequence[float], int]
    ],
) -> bytes:
    """trajectory_msgs/JointTrajectory stamped `ns`; each point is (positions, velocities,
    accelerations, effort, time_from_start [ns])."""
    buf = bytearray(HEADER_LE)
    _put_header(buf, ns, frame_id)
    _put_strings(buf, joint_names)
    buf += _PAD[-(len(buf) - 4) % 4]
    buf += _U32.pack(len(points))
    for positions, velocities, accelerations, effort, offset_ns in points:
        _put_doubles(buf, positions)
        _put_doubles(buf, velocities)
        _put_doubles(buf, accelerations)
        _put_doubles(buf, effort)
        buf += _PAD[-(len(buf) - 4) % 4]
        sec, nanosec = divmod(offset_ns, 1_000_000_000)
        try:
            buf += _STAMP.pack(sec, nanosec)
        except struct.error:
            raise CodecError(f'time_from_start {offset_ns} ns does not fit a Duration') from None
    return bytes(buf)


def encode_wrench_stamped(
    ns: int, frame_id: str, force: Sequence[float], torque: Sequence[float] = (0.0, 0.0, 0.0)
) -> bytes:
    """geometry_msgs/WrenchStamped stamped `ns`."""
    buf = bytearray(HEADER_LE)
    _put_header(buf, ns, frame_id)
    buf += _PAD[-(len(buf) - 4) % 8]
    buf += _doubles_struct(6).pack(*force, *torque)
    return bytes(buf)


def encode_clock(ns: int) -> bytes:
    """rosgraph_msgs/Clock holding `ns` (the simulation clock the lockstep plant publishes)."""
    sec, nanosec = divmod(ns, 1_000_000_000)
    try:
        return bytes(HEADER_LE) + _STAMP.pack(sec, nanosec)
    except struct.error:
        raise CodecError(f'clock {ns} ns does not fit builtin_interfaces/Time') from None


# -- reading ----------------------------------------------------------------------------------
class _Order:
    """The structs of one byte order."""

    def __init__(self, order: str) -> None:
        self.order = order
        self.u32 = struct.Struct(order + 'I')
        self.stamp = struct.Struct(order + 'iI')


_LE, _BE = _Order('<'), _Order('>')


def _order(data: bytes) -> _Order:
    if len(data) < 4:
        raise CodecError(f'{len(data)} bytes, fewer than the 4 of the CDR header')
    if data[0] != 0 or data[1] > 1:
        raise CodecError(f'not plain CDR (encapsulation {data[:2].hex()})')
    return _LE if data[1] else _BE


def _get_string(data: bytes, o: int, bo: _Order) -> tuple[str, int]:
    o += -(o - 4) % 4
    (n,) = bo.u32.unpack_from(data, o)
    o += 4
    if n < 1 or o + n > len(data):
        raise CodecError(f'string of {n} bytes at offset {o - 4} does not fit')
    if data[o + n - 1] != 0:
        raise CodecError(f'string at offset {o - 4} does not end with NUL')
    try:
        text = data[o : o + n - 1].decode()
    except UnicodeDecodeError:
        raise CodecError(f'string at offset {o - 4} is not UTF-8') from None
    return text, o + n


def _get_strings(data: bytes, o: int, bo: _Order) -> tuple[list[str], int]:
    o += -(o - 4) % 4
    (count,) = bo.u32.unpack_from(data, o)
    o += 4
    if count * 5 > len(data) - o:  # each string takes at least its length and a NUL
        raise CodecError(f'{count} strings at offset {o - 4} do not fit')
    out = []
    for _ in range(count):
        text, o = _get_string(data, o, bo)
        out.append(text)
    return out, o


def _get_doubles(data: bytes, o: int, bo: _Order) -> tuple[tuple[float, ...], int]:
    o += -(o - 4) % 4
    (count,) = bo.u32.unpack_from(data, o)
    o += 4
    if not count:
        return (), o
    o += -(o - 4) % 8
    if count * 8 > len(data) - o:
        raise CodecError(f'{count} float64 at offset {o} do not fit')
    return _doubles_struct(count, bo.order).unpack_from(data, o), o + 8 * count


def _get_header(data: bytes, bo: _Order) -> tuple[Header, int]:
    sec, nanosec = bo.stamp.unpack_from(data, 4)
    frame_id, o = _get_string(data, 12, bo)
    return Header(Time(sec, nanosec), frame_id), o


def decode_joint_state(data: bytes, whole: bool = False) -> JointStateData:
    """sensor_msgs/JointState from its CDR bytes; CodecError if they are not one.

    whole: the bytes are the message and no more (a bag's message, which rosbags reads so),
    so more than the final alignment padding after it is a CodecError too.
    """
    for layout in _READ_LAYOUTS.get(len(data), ()):  # a shape seen before: one struct call
        msg = layout.read(data)
        if msg is not None:
            return msg
    bo = _order(data)
    try:
        header, o = _get_header(data, bo)
        name, o = _get_strings(data, o, bo)
        position, o = _get_doubles(data, o, bo)
        velocity, o = _get_doubles(data, o, bo)
        effort, o = _get_doubles(data, o, bo)
    except struct.error:
        raise CodecError(f'JointState cut short ({len(data)} bytes)') from None
    if whole and o < len(data) - 3:
        raise CodecError(f'{len(data) - o} bytes after the JointState')
    if o == len(data) and bo is _LE and _read_layouts < _MAX_LAYOUTS:
        _keep_read_layout(header.frame_id, name, position, velocity, effort, data)
    return JointStateData(header, name, position, velocity, effort)


_READ_LAYOUTS: dict[int, list[_JointStateLayout]] = {}  # by message size
_read_layouts = 0


def _keep_read_layout(
    frame_id: str,
    name: list[str],
    position: Sequence[float],
    velocity: Sequence[float],
    effort: Sequence[float],
    data: bytes,
) -> None:
    """Keep the layout of a message just read the long way, if it reads it the short way."""
    global _read_layouts
    try:
        layout = _JointStateLayout(
            frame_id, tuple(name), (len(position), len(velocity), len(effort))
        )
    except CodecError:
        return
    if layout.size == len(data) and layout.read(data) is not None:
        _READ_LAYOUTS.setdefault(len(data), []).append(layout)
        _read_layouts += 1


def decode_joint_trajectory(data: bytes) -> JointTrajectoryData:
    """trajectory_msgs/JointTrajectory from its CDR bytes; CodecError if they are not one."""
    bo = _order(data)
    try:
        header, o = _get_header(data, bo)
        names, o = _get_strings(data, o, bo)
        o += -(o - 4) % 4
        (count,) = bo.u32.unpack_from(data, o)
        o += 4
        if count * 24 > len(data) - o:  # four counts and a Duration at least
            raise CodecError(f'{count} trajectory points at offset {o - 4} do not fit')
        points = []
        for _ in range(count):
            positions, o = _get_doubles(data, o, bo)
            velocities, o = _get_doubles(data, o, bo)
            accelerations, o = _get_doubles(data, o, bo)
            effort, o = _get_doubles(data, o, bo)
            o += -(o - 4) % 4
            sec, nanosec = bo.stamp.unpack_from(data, o)
            o += 8
            points.append(
                TrajectoryPointData(
                    positions, velocities, accelerations, effort, Time(sec, nanosec)
                )
            )
    except struct.error:
        raise CodecError(f'JointTrajectory cut short ({len(data)} bytes)') from None
    return JointTrajectoryData(header, names, points)


def decode_wrench_stamped(data: bytes) -> WrenchStampedData:
    """geometry_msgs/WrenchStamped from its CDR bytes; CodecError if they are not one."""
    bo = _order(data)
    try:
        header, o = _get_header(data, bo)
        v = _doubles_struct(6, bo.order).unpack_from(data, o + -(o - 4) % 8)
    except struct.error:
        raise CodecError(f'WrenchStamped cut short ({len(data)} bytes)') from None
    return WrenchStampedData(header, Wrench(Vector3(*v[:3]), Vector3(*v[3:])))
