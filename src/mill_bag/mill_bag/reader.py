"""Reading a rosbag2 bag (MCAP or sqlite3 storage) or a bare .mcap file, by topic and type.

`open_bag(path)` gives a `Bag`; `Bag.read()` yields (topic, type, log_time,
publish_time, data) with the data still CDR, so a reader decodes only what it
needs (`mill_bag.types.decode`). Only topic names and types are needed, so bags
of `ros2 bag record` (MCAP or sqlite3 storage) read like ours.

An MCAP file without footer (the recording was killed) is read up to its last
complete record, and `Bag.truncated` lists it: the writer flushes whole chunks, so
that is every message up to the last flush. `mill_bag.recover` rewrites it. A bag the
writer cut short (a full disk) says why in metadata.yaml: `Bag.cut_short`.
"""

from __future__ import annotations

import io
import json
import struct
from collections.abc import Collection, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from mill_bag.errors import BagError
from mill_bag.writer import CUT_SHORT

MCAP_MAGIC = b'\x89MCAP0\r\n'
Row = tuple[str, str, int, int | None, bytes]  # topic, type, log time, publish time, CDR


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

    @property
    def custom_data(self) -> dict[str, str]:
        """What the writer noted of the bag in metadata.yaml (`custom_data`); {} if nothing
        (a bare .mcap file, a bag without the field)."""
        info = (self.metadata or {}).get('rosbag2_bagfile_information') or {}
        custom = info.get('custom_data') if isinstance(info, dict) else None
        return {str(k): str(v) for k, v in custom.items()} if isinstance(custom, dict) else {}

    @property
    def cut_short(self) -> str | None:
        """Why the recording ended before it was closed (a full disk), as the writer noted
        it in metadata.yaml (`custom_data: cut_short`); None if it did not say so."""
        return self.custom_data.get(CUT_SHORT) or None

    def noted_counts(self, key: str) -> dict[str, int] | None:
        """Per-topic counts the writer noted under `key` (mill_bag.writer.counts_note);
        None where it noted none, or one that cannot be read."""
        text = self.custom_data.get(key)
        if text is None:
            return None
        try:
            return {str(t): int(n) for t, n in json.loads(text).items()}
        except (ValueError, TypeError, AttributeError):
            return None

    def read(self, topics: Collection[str] | None = None) -> Iterator[Row]:
        self.counts.clear()
        self.truncated.clear()
        for path in self.files:
            if self.storage == 'mcap':
                yield from self._read_mcap(path, topics)
            else:
                yield from self._read_rosbags(topics)
                break

    def _read_mcap(self, path: Path, topics: Collection[str] | None) -> Iterator[Row]:
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

        def record(buf: bytes, start: int, stop: int) -> ReadDataStream:
            return ReadDataStream(io.BytesIO(buf[start:stop]))

        def walk(buf: bytes, pos: int, stop: int, top: bool) -> Iterator[Row]:
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

    def _read_rosbags(self, topics: Collection[str] | None) -> Iterator[Row]:
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
