"""rosbag2 bags in MCAP storage: writing, reading, recovering, and turning them into RunRecords.

ROS-free (no rclpy): the report reads bags without a ROS graph. The file
format is left to maintained libraries: `mcap` writes the MCAP files and, when
reading, parses their schema, channel and chunk records (decompression, CRC);
`rosbags` provides the message definitions, type hashes and the CDR decoder,
and reads sqlite3 bags. What this module adds is the rosbag2 layout around
them, as `ros2 bag record -s mcap` writes it in Jazzy:

    BAG/metadata.yaml        rosbag2_bagfile_information, version 9
    BAG/BAG_0.mcap           profile "ros2"; schema encoding ros2msg, message encoding cdr;
                             channel metadata offered_qos_profiles (YAML) and topic_type_hash

Writing is chunked: `BagWriter.flush()` closes the current MCAP chunk and
hands it to the operating system, and rewrites metadata.yaml, so a recorder
that flushes every half second loses at most that much data to a hard kill.
A bag whose MCAP file has no footer (the recorder was killed) is read up to
its last complete record; `recover()` rewrites it as a complete bag.

The reader needs only topic names and types, so bags written by
`ros2 bag record` (MCAP or sqlite3 storage) work as well as ours.
"""

from __future__ import annotations

import argparse
import io
import operator
import os
import struct
import sys
from collections.abc import Collection, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from mill_common.signals import AXES
from mill_common.timebase import job_steps

from mill_bringup.metrics import RunRecord
from mill_common import topics as topic_names

MCAP_MAGIC = b'\x89MCAP0\r\n'
ROSBAG2_VERSION = 9
JOINT_STATE = 'sensor_msgs/msg/JointState'
JOINT_TRAJECTORY = 'trajectory_msgs/msg/JointTrajectory'
WRENCH_STAMPED = 'geometry_msgs/msg/WrenchStamped'
CLOCK = 'rosgraph_msgs/msg/Clock'
DIAGNOSTIC_ARRAY = 'diagnostic_msgs/msg/DiagnosticArray'
COMPRESSIONS = ('zstd', 'lz4', 'none')


class BagError(ValueError):
    """A bag that cannot be written or read as asked; str() says why in one line."""


# -- message types ---------------------------------------------------------------------------


@lru_cache(maxsize=1)
def typestore():
    """rosbags' store of the ROS 2 Jazzy message types (more are added from share/*/msg)."""
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_JAZZY)


def _msg_file(msgtype: str) -> Path | None:
    """The installed .msg file of a type, where rosbag2 finds definitions (ament index)."""
    pkg, _, name = msgtype.partition('/msg/')
    try:
        from ament_index_python.packages import get_package_share_directory

        path = Path(get_package_share_directory(pkg)) / 'msg' / f'{name}.msg'
    except Exception:
        path = Path(sys.prefix) / 'share' / pkg / 'msg' / f'{name}.msg'
    return path if path.is_file() else None


def _field_types(fields: Iterable) -> Iterator[str]:
    """Names of the message types a type's fields refer to (rosbags field definitions)."""
    for _name, (kind, detail) in fields:
        if kind.name in ('ARRAY', 'SEQUENCE'):
            kind, detail = detail[0]
        if kind.name == 'NAME':
            yield detail


def ensure_type(msgtype: str) -> None:
    """Make `msgtype` known to the typestore, loading its .msg files if Jazzy's store lacks it."""
    store = typestore()
    pending = [msgtype]
    loaded: set[str] = set()
    while pending:
        name = pending.pop()
        if name in store.fielddefs or name in loaded:
            continue
        path = _msg_file(name)
        if path is None:
            raise BagError(f'no message definition for {name}')
        from rosbags.typesys import get_types_from_msg

        types = get_types_from_msg(path.read_text(), name)
        store.register(types)
        loaded.add(name)
        for _consts, fields in types.values():
            pending.extend(t for t in _field_types(fields) if t not in store.fielddefs)


def message_definition(msgtype: str) -> tuple[str, str]:
    """(ros2msg definition with its dependencies, RIHS01 type hash) of a type."""
    ensure_type(msgtype)
    store = typestore()
    msgdef, _ = store.generate_msgdef(msgtype, ros_version=2)
    return msgdef, store.hash_rihs01(msgtype)


def sim_stamped(msgtype: str) -> bool:
    """True if the message carries a stamp of the graph's clock: a std_msgs/Header first, or Clock.

    Other builtin_interfaces/Time stamps (rcl_interfaces/Log, ParameterEvent) are wall
    time and are not used as sim time.
    """
    if msgtype == CLOCK:
        return True
    try:
        ensure_type(msgtype)
    except BagError:
        return False
    fields = typestore().fielddefs[msgtype][1]
    return bool(fields) and fields[0][1][1] == 'std_msgs/msg/Header'


def cdr_stamp_ns(data: bytes) -> int | None:
    """The leading builtin_interfaces/Time of a CDR message (a Header's stamp, Clock.clock) [ns].

    CDR starts with a 4-byte encapsulation header (00 00 big endian, 00 01 little
    endian); the stamp (int32 sec, uint32 nanosec) follows at offset 4.
    """
    if len(data) < 12 or data[0] != 0 or data[1] > 1:
        return None
    sec, nanosec = struct.unpack_from('<iI' if data[1] else '>iI', data, 4)
    return sec * 1_000_000_000 + nanosec


def decode(msgtype: str, data: bytes) -> Any:
    """A CDR message as an object with the message's field names (as rclpy's).

    sensor_msgs/JointState, 80 % of a run's messages, is read by `joint_state_cdr`
    (4x faster); everything else, and any JointState it does not accept, by rosbags.
    """
    if msgtype == JOINT_STATE:
        msg = joint_state_cdr(data)
        if msg is not None:
            return msg
    return typestore().deserialize_cdr(data, msgtype)


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

    def __init__(self, header, name, position, velocity, effort) -> None:
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
    endian, inconsistent lengths), which decode() hands to rosbags. Checked against
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
        tuple(len(a) for a in arrays),
        frame_id,
        tuple(names),
    )
    _LAYOUTS.setdefault(len(data), []).append(layout)
    return JointStateData(_Header(_Stamp(sec, nanosec), frame_id), names, *arrays)


# -- writing ---------------------------------------------------------------------------------


@dataclass
class TopicInfo:
    name: str
    msgtype: str
    qos: list[dict]
    type_hash: str
    channel_id: int
    count: int = 0


class BagWriter:
    """A rosbag2 bag in MCAP storage, written in chunks.

    `add_topic` registers a topic (schema + channel with its offered QoS), `write`
    adds one serialized message, `flush` closes the chunk, writes it to the file and
    refreshes metadata.yaml, `close` writes the MCAP summary and the final metadata.
    """

    def __init__(self, path: Path, compression: str = 'zstd', chunk_size: int = 1 << 20) -> None:
        from mcap.writer import CompressionType, Writer

        if compression not in COMPRESSIONS:
            raise BagError(f'compression must be one of {", ".join(COMPRESSIONS)}')
        self.path = Path(path)
        if self.path.exists():
            raise BagError(f'{self.path} exists already; a bag is never overwritten')
        try:
            self.path.mkdir(parents=True)
        except OSError as exc:
            raise BagError(f'cannot create bag directory {self.path}: {exc.strerror}') from None
        self.file_name = f'{self.path.name}_0.mcap'
        self._file = open(self.path / self.file_name, 'xb')  # noqa: SIM115 (closed in close())
        kind = {
            'zstd': CompressionType.ZSTD,
            'lz4': CompressionType.LZ4,
            'none': CompressionType.NONE,
        }[compression]
        self._mcap = Writer(self._file, chunk_size=chunk_size, compression=kind)
        self._mcap.start(profile='ros2', library=f'mill recorder ({_mcap_library()})')
        self.topics: dict[str, TopicInfo] = {}
        self._schemas: dict[str, int] = {}
        self.message_count = 0
        self.start_ns: int | None = None
        self.end_ns: int | None = None
        self.closed = False
        self.write_metadata()

    def add_topic(
        self, name: str, msgtype: str, qos: list[dict], type_hash: str | None = None
    ) -> TopicInfo:
        msgdef, rihs01 = message_definition(msgtype)
        schema_id = self._schemas.get(msgtype)
        if schema_id is None:
            schema_id = self._mcap.register_schema(msgtype, 'ros2msg', msgdef.encode())
            self._schemas[msgtype] = schema_id
        type_hash = type_hash or rihs01
        channel_id = self._mcap.register_channel(
            name,
            'cdr',
            schema_id,
            {'offered_qos_profiles': dump_yaml(qos), 'topic_type_hash': type_hash},
        )
        info = TopicInfo(name, msgtype, qos, type_hash, channel_id)
        self.topics[name] = info
        return info

    def write(self, topic: TopicInfo, log_time: int, publish_time: int, data: bytes) -> None:
        self._mcap.add_message(topic.channel_id, log_time, data, publish_time, topic.count)
        topic.count += 1
        self.message_count += 1
        if self.start_ns is None or log_time < self.start_ns:
            self.start_ns = log_time
        if self.end_ns is None or log_time > self.end_ns:
            self.end_ns = log_time

    def flush(self) -> None:
        """Close the current chunk, hand it to the OS and refresh metadata.yaml."""
        self._mcap.flush()
        self.write_metadata()

    def metadata(self) -> dict:
        return bag_metadata(
            [self.file_name],
            list(self.topics.values()),
            self.start_ns or 0,
            (self.end_ns or 0) - (self.start_ns or 0),
        )

    def write_metadata(self) -> None:
        write_metadata_file(self.path, self.metadata())

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        info = self.metadata()
        self._mcap.add_metadata(
            'rosbag2', {'serialized_metadata': dump_yaml(info['rosbag2_bagfile_information'])}
        )
        self._mcap.finish()
        self._file.flush()
        os.fsync(self._file.fileno())
        self._file.close()
        write_metadata_file(self.path, info)

    @property
    def size_bytes(self) -> int:
        return (self.path / self.file_name).stat().st_size


def _mcap_library() -> str:
    from mcap.writer import LIBRARY_IDENTIFIER

    return LIBRARY_IDENTIFIER


_DUMPER = getattr(yaml, 'CSafeDumper', yaml.SafeDumper)  # libyaml when there: 10x faster


def dump_yaml(value: Any) -> str:
    return yaml.dump(value, Dumper=_DUMPER, default_flow_style=False, sort_keys=False).strip()


def bag_metadata(
    files: Sequence[str], topics: Sequence[TopicInfo], start_ns: int, duration_ns: int
) -> dict:
    """metadata.yaml of a rosbag2 bag (version 9, as Jazzy writes it)."""
    count = sum(t.count for t in topics)
    return {
        'rosbag2_bagfile_information': {
            'version': ROSBAG2_VERSION,
            'storage_identifier': 'mcap',
            'duration': {'nanoseconds': int(duration_ns)},
            'starting_time': {'nanoseconds_since_epoch': int(start_ns)},
            'message_count': count,
            'topics_with_message_count': [
                {
                    'topic_metadata': {
                        'name': t.name,
                        'type': t.msgtype,
                        'serialization_format': 'cdr',
                        'offered_qos_profiles': t.qos,
                        'type_description_hash': t.type_hash,
                    },
                    'message_count': t.count,
                }
                for t in topics
            ],
            'compression_format': '',
            'compression_mode': '',
            'relative_file_paths': list(files),
            'files': [
                {
                    'path': f,
                    'starting_time': {'nanoseconds_since_epoch': int(start_ns)},
                    'duration': {'nanoseconds': int(duration_ns)},
                    'message_count': count,
                }
                for f in files
            ],
            'custom_data': {},
            'ros_distro': 'jazzy',
        }
    }


def write_metadata_file(bag_dir: Path, metadata: dict) -> None:
    """metadata.yaml, replaced atomically (a reader never sees half a file)."""
    tmp = bag_dir / 'metadata.yaml.tmp'
    tmp.write_text(dump_yaml(metadata) + '\n')
    tmp.replace(bag_dir / 'metadata.yaml')


# -- reading ---------------------------------------------------------------------------------


@dataclass
class Bag:
    """A rosbag2 bag (directory with metadata.yaml) or a bare .mcap file, opened for reading.

    `read()` yields (topic, type, log_time, publish_time, data) in file order and counts
    every topic's messages on the way; publish_time is None where the storage has none.
    """

    path: Path
    storage: str
    files: list[Path]
    metadata: dict | None = None
    counts: dict[str, int] = field(default_factory=dict)
    types: dict[str, str] = field(default_factory=dict)
    qos: dict[str, str] = field(default_factory=dict)
    truncated: list[Path] = field(default_factory=list)

    @property
    def name(self) -> str:
        return self.path.name

    def read(
        self, topics: Collection[str] | None = None
    ) -> Iterator[tuple[str, str, int, int | None, bytes]]:
        self.counts.clear()
        self.truncated.clear()
        for path in self.files:
            if self.storage == 'mcap':
                yield from self._read_mcap(path, topics)
            else:
                yield from self._read_rosbags(topics)
                break

    def _read_mcap(self, path: Path, topics: Collection[str] | None):
        """Schema, channel and chunk records are read by mcap's record classes, chunks
        decompressed and CRC-checked by mcap. Records are walked by their framing (opcode
        u8, length u64) and message records read by their fixed header (channel u16,
        sequence u32, log time u64, publish time u64, data): a Python object per message
        and per message-index entry would take seconds for a whole job's 600 000 messages.
        The summary section after DataEnd is not needed and not read."""
        from mcap.data_stream import ReadDataStream
        from mcap.exceptions import McapError
        from mcap.records import Channel, Chunk, Schema
        from mcap.stream_reader import get_chunk_data_stream

        data = path.read_bytes()
        if not data.startswith(MCAP_MAGIC):
            raise BagError(f'{path}: not an MCAP file')
        complete = data.endswith(MCAP_MAGIC) and len(data) > 2 * len(MCAP_MAGIC)
        end = complete_prefix(data)
        if not complete:
            self.truncated.append(path)
        schemas: dict[int, str] = {}
        channels: dict[int, tuple[str, str, bool]] = {}
        counts = self.counts
        header = struct.Struct('<HIQQ')
        frame = struct.Struct('<BQ')

        def record(buf: bytes, start: int, stop: int):
            return ReadDataStream(io.BytesIO(buf[start:stop]))

        def walk(buf: bytes, pos: int, stop: int, top: bool):
            while pos < stop:
                opcode, length = frame.unpack_from(buf, pos)
                start, pos = pos + 9, pos + 9 + length
                if opcode == 0x05:  # message
                    cid, _seq, log_time, publish_time = header.unpack_from(buf, start)
                    topic, msgtype, wanted = channels[cid]
                    counts[topic] += 1
                    if wanted:
                        yield topic, msgtype, log_time, publish_time, buf[start + 22 : pos]
                elif opcode == 0x06 and top:  # chunk
                    chunk = Chunk.read(record(buf, start, pos))
                    stream, size = get_chunk_data_stream(chunk, validate_crc=True)
                    yield from walk(stream.read(size), 0, size, False)
                elif opcode == 0x03:  # schema
                    schema = Schema.read(record(buf, start, pos))
                    schemas[schema.id] = schema.name
                elif opcode == 0x04:  # channel
                    channel = Channel.read(record(buf, start, pos))
                    msgtype = schemas.get(channel.schema_id, '')
                    wanted = topics is None or channel.topic in topics
                    channels[channel.id] = (channel.topic, msgtype, wanted)
                    self.types[channel.topic] = msgtype
                    self.qos[channel.topic] = channel.metadata.get('offered_qos_profiles', '')
                    counts.setdefault(channel.topic, 0)
                elif opcode in (0x0F, 0x02) and top:  # data end, footer: the summary follows
                    return

        try:
            yield from walk(data, len(MCAP_MAGIC), end, True)
        except (McapError, struct.error, KeyError, ValueError, IndexError) as exc:
            raise BagError(f'{path}: damaged MCAP file ({exc or type(exc).__name__})') from None

    def _read_rosbags(self, topics: Collection[str] | None):
        from rosbags.rosbag2 import Reader

        try:
            with Reader(self.path) as reader:
                for c in reader.connections:
                    self.types[c.topic] = c.msgtype
                    self.counts.setdefault(c.topic, 0)
                conns = [c for c in reader.connections if topics is None or c.topic in topics]
                for c in reader.connections:
                    self.counts[c.topic] = c.msgcount
                for conn, timestamp, data in reader.messages(connections=conns):
                    yield conn.topic, conn.msgtype, timestamp, None, data
        except Exception as exc:  # rosbags raises several types; all mean "unreadable"
            raise BagError(f'{self.path}: cannot read the bag ({exc})') from None


def complete_prefix(data: bytes) -> int:
    """Length of the longest prefix of an MCAP file made of whole records.

    Each top-level record is opcode (1 byte), length (uint64), body; a recording
    killed mid-write ends in a partial record, which this cuts off.
    """
    pos = len(MCAP_MAGIC)
    end = len(data)
    while pos + 9 <= end:
        (length,) = struct.unpack_from('<Q', data, pos + 1)
        if pos + 9 + length > end:
            break
        pos += 9 + length
    return pos


def open_bag(path: str | Path) -> Bag:
    """Open a bag directory (metadata.yaml + storage files) or a single .mcap file."""
    path = Path(path)
    if not path.exists():
        raise BagError(f'no such bag: {path}')
    if path.is_file():
        if path.suffix != '.mcap':
            raise BagError(f'{path} is neither a bag directory nor an .mcap file')
        return Bag(path, 'mcap', [path])
    meta_path = path / 'metadata.yaml'
    if meta_path.is_file():
        try:
            meta = yaml.safe_load(meta_path.read_text())
            info = meta['rosbag2_bagfile_information']
            storage = info.get('storage_identifier', 'mcap')
            names = list(info.get('relative_file_paths') or [])
        except (yaml.YAMLError, KeyError, TypeError, AttributeError):
            raise BagError(f'{meta_path}: not a rosbag2 metadata file') from None
        if storage not in ('mcap', 'sqlite3'):
            raise BagError(f'{path}: storage {storage!r} is not supported (mcap, sqlite3)')
        files = [path / Path(n).name for n in names]
        missing = [str(f) for f in files if not f.is_file()]
        if missing:
            raise BagError(f'{path}: storage files missing: {", ".join(missing)}')
        if not files:
            raise BagError(f'{path}: metadata.yaml lists no storage file')
        return Bag(path, storage, files, meta)
    files = sorted(path.glob('*.mcap'))
    if not files:
        raise BagError(f'{path} is not a rosbag2 bag: no metadata.yaml and no .mcap file')
    return Bag(path, 'mcap', files)


# -- recovering a killed recording -----------------------------------------------------------


def recover(path: str | Path) -> tuple[int, int]:
    """Rewrite the truncated MCAP files of a killed recording as complete ones.

    Every message of the complete records is kept, with its channel metadata (QoS,
    type hash); metadata.yaml is rebuilt from the data. The original file is kept
    next to it as NAME.mcap.truncated. Returns (messages kept, files rewritten).
    """
    from mcap.writer import CompressionType, Writer

    bag = open_bag(path)
    if bag.storage != 'mcap':
        raise BagError(f'{bag.path}: only MCAP bags can be recovered')
    kept = rewritten = 0
    rows = list(bag.read())
    if not bag.truncated:
        return len(rows), 0
    per_file: dict[str, list[TopicInfo]] = {}
    for src in bag.truncated:
        tmp = src.with_suffix('.mcap.recovering')
        with open(tmp, 'wb') as out:
            writer = Writer(out, compression=CompressionType.ZSTD)
            writer.start(profile='ros2', library=f'mill recover ({_mcap_library()})')
            sub = open_bag(src) if bag.path.is_dir() else bag
            sub_rows = list(sub.read())
            infos: dict[str, TopicInfo] = {}
            schemas: dict[str, int] = {}
            start = end = None
            for topic, msgtype, log_time, publish_time, data in sub_rows:
                info = infos.get(topic)
                if info is None:
                    msgdef, rihs01 = message_definition(msgtype)
                    if msgtype not in schemas:
                        schemas[msgtype] = writer.register_schema(
                            msgtype, 'ros2msg', msgdef.encode()
                        )
                    qos_text = sub.qos.get(topic, '')
                    qos = yaml.safe_load(qos_text) if qos_text else []
                    channel = writer.register_channel(
                        topic,
                        'cdr',
                        schemas[msgtype],
                        {'offered_qos_profiles': qos_text, 'topic_type_hash': rihs01},
                    )
                    info = infos[topic] = TopicInfo(topic, msgtype, qos or [], rihs01, channel)
                writer.add_message(info.channel_id, log_time, data, publish_time or log_time)
                info.count += 1
                start = log_time if start is None else min(start, log_time)
                end = log_time if end is None else max(end, log_time)
            writer.finish()
        src.rename(src.with_name(src.name + '.truncated'))
        tmp.rename(src)
        per_file[src.name] = list(infos.values())
        kept += sum(i.count for i in infos.values())
        rewritten += 1
        if bag.path.is_dir():
            write_metadata_file(
                bag.path,
                bag_metadata([src.name], per_file[src.name], start or 0, (end or 0) - (start or 0)),
            )
    return kept, rewritten


# -- bag -> RunRecord ------------------------------------------------------------------------


def record_topics(axes: Sequence[str]) -> dict[str, str]:
    """Topics (and types) a RunRecord is built from."""
    out = {}
    for axis in axes:
        out[topic_names.state(axis)] = JOINT_STATE
        out[topic_names.estimate(axis)] = JOINT_STATE
        out[topic_names.joint_command(axis)] = JOINT_STATE
    out[topic_names.REFERENCE] = JOINT_TRAJECTORY
    out[topic_names.GROUND_TRUTH] = JOINT_STATE
    out[topic_names.CUTTING_FORCE] = WRENCH_STAMPED
    return out


def _ns(time_msg: Any) -> int:
    return time_msg.sec * 1_000_000_000 + time_msg.nanosec


def build_record(
    messages: Iterable[tuple[str, Any]],
    axes: Sequence[str],
    n: int,
    dt_ns: int,
    listened: Iterable[str],
) -> tuple[RunRecord, dict[str, int]]:
    """Decoded messages (topic, message) -> RunRecord of n samples at t = k T.

    The one place where messages become signals: the runner's monitor and the
    bag reader both call it. A message belongs to sample k when its header stamp
    is exactly k T (0 <= k < n); a repeated stamp overwrites with the same values.
    Also returns, per listened per-sample topic, how many of the n samples are missing.
    """
    rec = RunRecord.empty(n, dt_ns / 1e9)
    s = rec.signals
    seen: dict[str, set[int]] = {t: set() for t in listened if t != topic_names.REFERENCE}
    position, torque, force = s['position'], s['torque'], s['force']
    est_v, est_d = s['estimate_velocity'], s['estimate_disturbance']
    ref_p, ref_v = s['reference'], s['reference_velocity']
    true_v, true_d = s['true_velocity'], s['true_disturbance']

    def on_state(k, msg, i):
        position[k, i] = msg.position[0]

    def on_estimate(k, msg, i):
        est_v[k, i] = msg.velocity[0]
        est_d[k, i] = msg.effort[0]

    def on_command(k, msg, i):
        torque[k, i] = msg.effort[0]

    def on_truth(k, msg, _i):
        for j, name in enumerate(msg.name):
            i = AXES.index(name)
            true_v[k, i] = msg.velocity[j]
            true_d[k, i] = msg.effort[j]

    def on_force(k, msg, _i):
        f = msg.wrench.force
        force[k] = (f.x, f.y, f.z)

    handlers: dict[str, tuple] = {
        topic_names.GROUND_TRUTH: (on_truth, None),
        topic_names.CUTTING_FORCE: (on_force, None),
    }
    for axis in axes:
        i = AXES.index(axis)
        handlers[topic_names.state(axis)] = (on_state, i)
        handlers[topic_names.estimate(axis)] = (on_estimate, i)
        handlers[topic_names.joint_command(axis)] = (on_command, i)

    for topic, msg in messages:
        k, rem = divmod(_ns(msg.header.stamp), dt_ns)
        if rem != 0 or not 0 <= k < n:
            continue
        if topic == topic_names.REFERENCE:
            for point in msg.points:
                kp = k + _ns(point.time_from_start) // dt_ns
                if kp >= n:
                    break
                for j, name in enumerate(msg.joint_names):
                    if name in axes:
                        i = AXES.index(name)
                        ref_p[kp, i] = point.positions[j]
                        ref_v[kp, i] = point.velocities[j]
            continue
        handler = handlers.get(topic)
        if handler is None:
            continue
        handler[0](k, msg, handler[1])
        if topic in seen:
            seen[topic].add(k)
    missing = {t: n - len(ks) for t, ks in seen.items()}
    return rec, missing


def record_from_raw(
    raw: dict[str, list[bytes]],
    types: dict[str, str],
    axes: Sequence[str],
    n: int,
    dt_ns: int,
    workers: int = 1,
) -> tuple[RunRecord, dict[str, int]]:
    """Serialized messages per topic -> decode -> build_record; what the monitor and the bag
    reader both call. With workers > 1 the topics are split between forked processes, each
    running build_record on its share; every (sample, axis) value comes from one topic, so
    the merged record is the one a single call gives."""
    listened = list(raw)
    if workers <= 1:
        messages = ((t, decode(types[t], d)) for t in listened for d in raw[t])
        return build_record(messages, axes, n, dt_ns, listened)
    import multiprocessing

    global _SHARED  # read by the forked workers, not pickled
    groups: list[list[str]] = [[] for _ in range(workers)]
    loads = [0] * workers
    for topic in sorted(listened, key=lambda t: -len(raw[t])):
        i = loads.index(min(loads))
        groups[i].append(topic)
        loads[i] += len(raw[topic])
    _SHARED = (raw, types, list(axes), n, dt_ns)
    try:
        with multiprocessing.get_context('fork').Pool(workers) as pool:
            parts = pool.map(_record_part, [g for g in groups if g])
    finally:
        _SHARED = None
    rec = RunRecord.empty(n, dt_ns / 1e9)
    missing: dict[str, int] = {}
    for signals, part_missing in parts:
        for name, values in signals.items():
            have = ~np.isnan(values)
            rec.signals[name][have] = values[have]
        missing.update(part_missing)
    return rec, missing


_SHARED: tuple | None = None


def _record_part(topics_part: list[str]) -> tuple[dict[str, np.ndarray], dict[str, int]]:
    raw, types, axes, n, dt_ns = _SHARED
    messages = ((t, decode(types[t], d)) for t in topics_part for d in raw[t])
    rec, missing = build_record(messages, axes, n, dt_ns, topics_part)
    return rec.signals, missing


# -- the run in a bag ------------------------------------------------------------------------


@dataclass
class BagRun:
    """What a bag holds of a mill run: its RunRecord and what the report needs besides."""

    bag: Bag
    axes: list[str]
    dt_ns: int
    n: int
    record: RunRecord
    missing: dict[str, int]
    end_time: float | None
    job_end_source: str
    state_wall_ns: np.ndarray | None  # wall time each sample of the first state arrived [ns]
    plant_status: dict[str, str]
    feed_override: list[tuple[int, float]] | None
    message_count: int
    size_bytes: int
    notes: list[str] = field(default_factory=list)


def read_run(path: str | Path) -> BagRun:
    """Read a bag of a mill run into a RunRecord, by topic names and types only.

    The sample period is the greatest common divisor of the state stamps; the
    number of samples comes from the trajectory's job status on /diagnostics
    (end_time, as the runner computes it), or, without it, from the last sample
    every state topic has.
    """
    bag = open_bag(path)
    wanted_types = record_topics(AXES)
    raw: dict[str, list[bytes]] = {}
    walls: dict[str, list[int | None]] = {}  # publish times of the state messages
    statuses: list[Any] = []
    feed: list[tuple[int, bytes]] = []
    feed_type = ''
    for topic, msgtype, log_time, publish_time, data in bag.read():
        if topic in wanted_types:
            if msgtype != wanted_types[topic]:
                raise BagError(
                    f'{bag.path}: topic {topic} has type {msgtype}, expected {wanted_types[topic]}'
                )
            raw.setdefault(topic, []).append(data)
            if topic.endswith('/state'):
                walls.setdefault(topic, []).append(publish_time)
        elif topic == topic_names.DIAGNOSTICS and msgtype == DIAGNOSTIC_ARRAY:
            statuses.append(decode(msgtype, data))
        elif topic == topic_names.FEED_OVERRIDE:
            feed_type = msgtype
            feed.append((log_time, data))
    total = sum(bag.counts.values())
    if total == 0:
        raise BagError(f'{bag.path} holds no messages')
    axes = [a for a in AXES if topic_names.state(a) in raw]
    if not axes:
        present = ', '.join(sorted(bag.counts)) or 'none'
        raise BagError(
            f'{bag.path} holds no mill run: no /mill/<axis>/state topic '
            f'(sensor_msgs/msg/JointState); its topics: {present}'
        )
    first = topic_names.state(axes[0])
    first_stamps = [cdr_stamp_ns(d) for d in raw[first]]
    stamps = np.array(sorted({s for s in first_stamps if s is not None}), dtype=np.int64)
    diffs = np.diff(stamps)
    dt_ns = int(np.gcd.reduce(diffs[diffs > 0])) if (diffs > 0).any() else 0
    if dt_ns <= 0:
        raise BagError(f'{bag.path}: fewer than two samples on {first}')
    notes = []
    end_time, source = _job_end(statuses)
    if end_time is not None:
        n = job_steps(end_time, dt_ns)
    else:
        last = min(max(cdr_stamp_ns(d) or 0 for d in raw[topic_names.state(a)]) for a in axes)
        n = last // dt_ns + 1
        source = 'last sample of every state topic (no job status on /diagnostics)'
        notes.append('no job status on /diagnostics: every sample up to the last state is used')
    listened = {t: raw[t] for t in record_topics(axes) if t in raw}
    to_decode = sum(len(v) for v in listened.values())
    workers = min(2, os.cpu_count() or 1) if to_decode > 100_000 else 1
    record, missing = record_from_raw(listened, wanted_types, axes, n, dt_ns, workers)
    # Wall-clock arrival of each sample of the first axis, where the storage has
    # a wall time besides the (sim) stamp: our recorder's and rosbag2's publish_time.
    wall = None
    pairs = [(s, w) for s, w in zip(first_stamps, walls[first], strict=True) if s is not None]
    if pairs and any(w is not None and w != s for s, w in pairs):
        by_stamp = {s: w for s, w in pairs if w is not None}
        wall = np.array([by_stamp.get(k * dt_ns, -1) for k in range(n)], dtype=np.int64)
    if bag.truncated:
        notes.append(
            'the bag was not closed (recorder killed?): read up to its last complete chunk'
        )
    feed_values = _feed_values(feed_type, feed, notes) if feed else None
    size = sum(f.stat().st_size for f in bag.files)
    return BagRun(
        bag=bag,
        axes=axes,
        dt_ns=dt_ns,
        n=n,
        record=record,
        missing={t: m for t, m in missing.items() if m},
        end_time=end_time,
        job_end_source=source,
        state_wall_ns=wall,
        plant_status=_plant_status(statuses),
        feed_override=feed_values,
        message_count=total,
        size_bytes=size,
        notes=notes,
    )


def _status_values(status: Any) -> dict[str, str]:
    return {kv.key: kv.value for kv in status.values}


def _job_end(statuses: list[Any]) -> tuple[float | None, str]:
    for array in statuses:
        for status in array.status:
            if status.name == 'mill_trajectory: job':
                values = _status_values(status)
                if 'end_time' in values:
                    return float(values['end_time']), 'job status on /diagnostics'
    return None, ''


def _plant_status(statuses: list[Any]) -> dict[str, str]:
    for array in reversed(statuses):
        for status in array.status:
            if status.name == 'mill_plant: lockstep':
                return _status_values(status) | {'message': status.message}
    return {}


def _feed_values(msgtype: str, feed: list, notes: list[str]) -> list[tuple[int, float]]:
    out = []
    for log_time, data in feed:
        try:
            msg = decode(msgtype, data)
        except Exception:
            notes.append(f'{topic_names.FEED_OVERRIDE}: cannot decode type {msgtype}')
            return []
        value = getattr(msg, 'data', None)
        if value is None:
            notes.append(f'{topic_names.FEED_OVERRIDE}: type {msgtype} has no numeric data')
            return []
        out.append((log_time, float(value)))
    return out


# -- command line: recover -------------------------------------------------------------------


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog='python -m mill_bringup.bag',
        description='Rosbag2 MCAP bag tools. recover: rewrite the MCAP file of a killed '
        'recording (no footer) as a complete bag that every reader opens.',
    )
    parser.add_argument('command', choices=['recover'])
    parser.add_argument('bag', help='bag directory or .mcap file')
    args = parser.parse_args(argv)
    try:
        kept, files = recover(args.bag)
    except BagError as exc:
        print(f'bag: error: {exc}', file=sys.stderr)
        return 1
    if files:
        print(f'{args.bag}: recovered {kept} messages in {files} file(s)')
    else:
        print(f'{args.bag}: complete already ({kept} messages)')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
