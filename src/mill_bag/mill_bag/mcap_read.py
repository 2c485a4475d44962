"""The messages of one MCAP file, read whole or around its damaged parts. ROS-free.

Schema, channel and chunk records are read by mcap's record classes, chunks decompressed
and CRC-checked by mcap. Records are walked by their framing (opcode u8, length u64) and
message records read by their fixed header (channel u16, sequence u32, log time u64, publish
time u64, data): a Python object per message and per message-index entry would take seconds
for a whole job's 600 000 messages. The summary after DataEnd is read only where the data
section is damaged (its channels and chunk index).

Damage. A chunk whose record, decompression, CRC or records fail is damaged, and none of its
messages is used. A record whose framing is broken (an opcode MCAP does not have, a length
past the end) hides where the next one starts: reading goes on at the next chunk the
summary's chunk index names or, without one, at the next offset where a whole chunk reads
(its CRC checks out), and everything in between is damaged. Message index records follow
chunks and nothing else, so a record followed by one, or one that is no message index, is
read as the chunk it was before its opcode was flipped. Messages whose channel was defined
only in a damaged part are lost with it. Each damaged part is a `Damage`, with the messages
lost and their log times where the file's indexes say (the message indexes after a chunk,
or the summary's chunk index). Strict reading (`damaged=None`) raises BagError at the first.

A file without footer (a killed recording) ends in a partial record; that is no damage.
"""

from __future__ import annotations

import contextlib
import struct
from collections.abc import Collection, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from mill_bag.errors import BagError
from mill_bag.mcap_index import (
    CHANNEL,
    CHUNK,
    DATA_END,
    FOOTER,
    FOOTER_SIZE,
    MCAP_MAGIC,
    MESSAGE,
    MESSAGE_INDEX,
    SCHEMA,
    Summary,
    following_times,
    index_end,
    index_ok,
    index_times,
    read_summary,
)
from mill_bag.mcap_index import FRAME as _FRAME
from mill_bag.mcap_index import read_record as _read

Row = tuple[str, str, int, int | None, bytes]  # topic, type, log time, publish time, CDR
_MESSAGE = struct.Struct('<HIQQ')
_TIMES = struct.Struct('<QQ')
_CHUNK = struct.Struct('<QQQII')  # start and end time, uncompressed size and CRC, compression
MAX_CHUNK = 1 << 30  # [bytes] uncompressed: more is a damaged size field, not a chunk


class Catalog(Protocol):
    """What a reader learns of a bag's topics (mill_bag.reader.Bag)."""

    counts: dict[str, int]
    types: dict[str, str]
    qos: dict[str, str]


@dataclass(frozen=True)
class Damage:
    """One damaged part of an MCAP file and what it cost."""

    path: Path
    where: str  # 'bytes 62-4097 (a chunk)'
    reason: str
    messages: int | None  # lost; None: not known
    first_ns: int | None = None  # their log times, where known
    last_ns: int | None = None

    def __str__(self) -> str:
        n = 'an unknown number of' if self.messages is None else str(self.messages)
        lost = f'{n} messages lost'
        if self.first_ns is not None and self.last_ns is not None:
            lost += f', log times {self.first_ns / 1e9:.9f} to {self.last_ns / 1e9:.9f} s'
        return f'{self.path}: {self.where}: {self.reason}; {lost}'


def _why(exc: Exception) -> str:
    return str(exc) or type(exc).__name__


def _where(start: int, stop: int, what: str) -> str:
    return f'bytes {start}-{stop} ({what})'


def _frames_ok(buf: bytes) -> None:
    """Raise if the records of a chunk do not fill it exactly."""
    pos = 0
    while pos < len(buf):
        pos += 9 + _FRAME.unpack_from(buf, pos)[1]
    if pos != len(buf):
        raise ValueError('records run past the end of the chunk')


class McapFile:
    """One MCAP file, its topics noted in `catalog` as `rows()` yields its messages."""

    def __init__(
        self,
        path: Path,
        catalog: Catalog,
        topics: Collection[str] | None = None,
        damaged: list[Damage] | None = None,
        hints: Mapping[int, tuple[str, str, str]] | None = None,
    ) -> None:
        self.path = path
        self.data = path.read_bytes()
        if not self.data.startswith(MCAP_MAGIC):
            raise BagError(f'{path}: not an MCAP file')
        self.complete = self.data.endswith(MCAP_MAGIC) and len(self.data) > 2 * len(MCAP_MAGIC)
        self.footer = len(self.data) - len(MCAP_MAGIC) - FOOTER_SIZE  # where a footer is
        self.catalog = catalog
        self.topics = topics
        self.damaged = damaged
        self.hints = hints or {}  # channel id -> topic, type, QoS YAML (mill_bag.reader)
        self.schemas: dict[int, str] = {}
        self.channels: dict[int, tuple[str, str, bool]] = {}
        self._summary: Summary | None = None
        self._orphans: dict[int, list[int]] = {}  # log times per channel defined nowhere

    # -- records ---------------------------------------------------------------------------
    def _define(self, op: int, buf: bytes, start: int, stop: int) -> None:
        from mcap.records import Channel, Schema

        if op == SCHEMA:
            schema = _read(Schema, buf, start, stop)
            self.schemas[schema.id] = schema.name
        else:
            channel = _read(Channel, buf, start, stop)
            self._channel(channel, self.schemas.get(channel.schema_id, ''))

    def _channel(self, channel: Any, msgtype: str) -> tuple[str, str, bool]:
        topic = channel.topic
        entry = self.channels[channel.id] = (
            topic,
            msgtype,
            self.topics is None or topic in self.topics,
        )
        self.catalog.types[topic] = msgtype
        self.catalog.qos[topic] = channel.metadata.get('offered_qos_profiles', '')
        self.catalog.counts.setdefault(topic, 0)
        return entry

    def _read_chunk(self, start: int, stop: int | None) -> tuple[bytes, int]:
        """The records of the chunk at `start`, decompressed and CRC-checked, and where it
        ends: where its frame says (`stop`, None if the frame is no chunk's), else where its
        own records length says. Either may be the damaged one: unless they agree, the end
        is the one a message index follows (as it follows every chunk of an indexed file),
        else one where a record can follow; a compressed stream may read whole with a few
        bytes more or less (a low byte of the frame's length flipped). Raises (the first
        failure) if it does not read."""
        failure: Exception | None = None
        found: list[tuple[bytes, int]] = []
        for bound in ([stop] if stop is not None else []) + [None]:
            try:
                buf, end, own_end = self._whole_chunk(start, bound)
            except Exception as exc:
                failure = failure or exc
                continue
            if end == stop == own_end:
                return buf, end
            found.append((buf, end))
        for buf, end in found:
            if index_ok(self.data, end):
                return buf, end
        for buf, end in found:
            if self._record_may_start(end):
                return buf, end
        if found:
            failure = failure or ValueError(f'no record can start where it ends ({found[0][1]})')
        assert failure is not None
        raise failure

    def _record_may_start(self, pos: int) -> bool:
        """A record can start at pos: a message index, or a valid opcode and length (or, in
        a killed recording, the end of the file)."""
        data = self.data
        if pos + 9 > len(data):
            return pos == len(data) and not self.complete
        op, length = _FRAME.unpack_from(data, pos)
        return index_ok(data, pos) or (0x01 <= op <= 0x0F and pos + 9 + length <= len(data))

    def _whole_chunk(self, start: int, bound: int | None) -> tuple[bytes, int, int]:
        """The records of the chunk record at `start`, where it ends, and where its own
        records length says it ends; its records end at `bound`, or (None) there."""
        from mcap.records import Chunk
        from mcap.stream_reader import get_chunk_data_stream

        data = self.data
        t0, t1, size, crc, n = _CHUNK.unpack_from(data, start + 9)
        pos = start + 9 + _CHUNK.size
        compression = data[pos : pos + n].decode()
        (length,) = struct.unpack_from('<Q', data, pos + n)
        pos += n + 8
        own_end = pos + length
        if bound is not None:
            length = bound - pos
        if pos + length > len(data):
            raise ValueError(f'its {length} bytes of records run past the end of the file')
        if size > MAX_CHUNK:
            raise ValueError(f'uncompressed size of {size} bytes')
        chunk = Chunk(compression, data[pos : pos + length], t1, t0, crc, size)
        stream, got = get_chunk_data_stream(chunk, validate_crc=True)
        if got != size:
            raise ValueError(f'{got} bytes uncompressed, {size} expected')
        return stream.read(got), pos + length, own_end

    def _walk(self, buf: bytes) -> Iterator[Row]:
        """The messages of a chunk's records (or of one top-level message record)."""
        pos, stop = 0, len(buf)
        frame, header = _FRAME.unpack_from, _MESSAGE.unpack_from
        counts, channels = self.catalog.counts, self.channels
        while pos < stop:
            op, length = frame(buf, pos)
            start, pos = pos + 9, pos + 9 + length
            if pos > stop:
                raise ValueError(f'a record of {length} bytes runs past the end of its chunk')
            if op == MESSAGE:
                cid, _seq, log_time, publish_time = header(buf, start)
                entry = channels.get(cid) or self._undefined(cid, log_time)
                if entry is None:
                    continue
                topic, msgtype, wanted = entry
                counts[topic] += 1
                if wanted:
                    yield topic, msgtype, log_time, publish_time, buf[start + 22 : pos]
            elif op in (SCHEMA, CHANNEL):
                self._define(op, buf, start, pos)

    def _undefined(self, cid: int, log_time: int) -> tuple[str, str, bool] | None:
        """A message of a channel no record before it defines (its definition was in a damaged
        part): defined in the summary, or, in a file of mill_bag's writer, by the `hints`
        (its channel ids count its topics in metadata.yaml's order); else lost."""
        from mcap.records import Channel, Header

        if self.damaged is None:
            raise ValueError(f'a message of channel {cid}, which no record defines')
        summary = self.summary()
        if cid in summary.channels:
            channel = summary.channels[cid]
            return self._channel(channel, summary.schemas.get(channel.schema_id, ''))
        if cid in self.hints and self.data[len(MCAP_MAGIC)] == 0x01:
            length = _FRAME.unpack_from(self.data, len(MCAP_MAGIC))[1]
            start = len(MCAP_MAGIC) + 9
            with contextlib.suppress(Exception):
                if _read(Header, self.data, start, start + length).library.startswith('mill '):
                    topic, msgtype, qos = self.hints[cid]
                    metadata = {'offered_qos_profiles': qos}
                    channel = Channel(
                        id=cid, topic=topic, message_encoding='cdr', schema_id=0, metadata=metadata
                    )
                    return self._channel(channel, msgtype)
        self._orphans.setdefault(cid, []).append(log_time)
        return None

    # -- the file ----------------------------------------------------------------------------
    def rows(self) -> Iterator[Row]:
        data, pos, end = self.data, len(MCAP_MAGIC), len(self.data)
        finished = False
        while pos + 9 <= end:
            op, length = _FRAME.unpack_from(data, pos)
            stop = pos + 9 + length
            framed = stop <= end and (0x01 <= op <= 0x0F or op >= 0x80)
            # Message indexes follow a chunk and nothing else: a record they follow was one.
            was_chunk = op != MESSAGE_INDEX and index_ok(data, stop)
            end_of_data = op == DATA_END or (op == FOOTER and pos == self.footer)
            if framed and end_of_data and not was_chunk:
                finished = True
                break
            plain = op not in (CHUNK, FOOTER) and (op != MESSAGE_INDEX or index_ok(data, pos))
            if framed and plain and not was_chunk:
                if op == MESSAGE:
                    yield from self._walk(data[pos:stop])
                elif op in (SCHEMA, CHANNEL):
                    try:
                        self._define(op, data, pos + 9, stop)
                    except Exception as exc:
                        where = _where(pos, stop, 'a definition')
                        self._damage(Damage(self.path, where, _why(exc), 0))
                pos = stop
                continue
            own = index_end(data, pos) if op == MESSAGE_INDEX and not was_chunk else 0
            if own and self._record_may_start(own):  # a message index whose frame is damaged
                why = f'its frame is damaged (length {length}), its own length is not'
                self._damage(Damage(self.path, _where(pos, own, 'a message index'), why, 0))
                pos = own
                continue
            try:  # a chunk, or a record that is one but for damage in its frame
                buf, stop = self._read_chunk(pos, stop if framed and op == CHUNK else None)
            except Exception as exc:
                if framed and op == MESSAGE_INDEX:  # after a chunk, not one: a damaged index
                    why = 'neither a message index nor a chunk'
                    self._damage(Damage(self.path, _where(pos, stop, 'a message index'), why, 0))
                    pos = stop
                    continue
                if framed:  # the chunk is damaged, its frame says where the next record is
                    self._damage(self._lost(pos, stop, 'a chunk', _why(exc)))
                    pos = stop
                    continue
                nxt = self._next_chunk(pos)
                if nxt is None and not self.complete:
                    return  # the partial last record of a killed recording
                stop = end if nxt is None else nxt
                self._damage(self._lost(pos, stop, 'records', 'record framing broken'))
                pos = stop
                continue
            if op != CHUNK or stop != pos + 9 + length:
                why = (
                    f'its frame is damaged (opcode {op:#04x}, length {length}), its fields are not'
                )
                self._damage(Damage(self.path, _where(pos, stop, 'a chunk'), why, 0))
            yield from self._chunk(pos, stop, buf)
            pos = stop
        if self.complete and not finished and pos < end:
            self._damage(Damage(self.path, _where(pos, end, 'the end'), 'no DataEnd record', None))
        for cid, times in self._orphans.items():
            why = 'its definition was in a damaged part'
            lost = Damage(self.path, f'channel {cid}', why, len(times), min(times), max(times))
            self._damage(lost)

    def _chunk(self, start: int, stop: int, buf: bytes) -> Iterator[Row]:
        """The messages of a chunk that read whole; strict: as they are read, else all or
        (if one of its records is damaged) none."""
        if self.damaged is None:
            yield from self._walk(buf)
            return
        counts = self.catalog.counts
        saved = dict(counts)
        try:
            rows = list(self._walk(buf))
        except Exception as exc:
            counts.clear()
            counts.update(saved)
            self._damage(self._lost(start, stop, 'a chunk', _why(exc)))
            return
        yield from rows

    def _next_chunk(self, pos: int) -> int | None:
        """Where reading goes on after a broken record at pos: the next chunk of the summary's
        chunk index (or its DataEnd), without one the next offset where a chunk reads whole."""
        summary = self.summary()
        if summary.chunks:
            after = [c.chunk_start_offset for c in summary.chunks if c.chunk_start_offset > pos]
            return min(after, default=summary.data_end)
        data, chunk = self.data, CHUNK.to_bytes(1, 'little')
        q = data.find(chunk, pos + 1)
        while q != -1:
            try:
                buf, _stop = self._read_chunk(q, None)
                _frames_ok(buf)
                return q
            except Exception:
                q = data.find(chunk, q + 1)
        return None

    def _lost(self, start: int, stop: int, what: str, reason: str) -> Damage:
        """What a damaged part data[start:stop] cost: the messages the summary's chunk index
        places in it (a complete file), else those of the message indexes that follow it,
        and their log times; else the times in the header of a chunk at start."""
        data, n, times = self.data, None, None
        chunks = self.summary().chunks
        if chunks:
            inside = [c for c in chunks if start <= c.chunk_start_offset < stop]
            times = index_times(data, [o for c in inside for o in c.message_index_offsets.values()])
            if times is None:
                times = [t for c in inside for t in (c.message_start_time, c.message_end_time)]
            else:
                n = len(times)
        else:
            times = following_times(data, stop, self.complete)
            n = None if times is None else len(times)
        if not times and n is None and data[start] == CHUNK and start + 25 <= len(data):
            times = list(_TIMES.unpack_from(data, start + 9))  # its header's
        first, last = (min(times), max(times)) if times else (None, None)
        return Damage(self.path, _where(start, stop, what), reason, n, first, last)

    def summary(self) -> Summary:
        if self._summary is None:
            self._summary = read_summary(self.data)
        return self._summary

    def _damage(self, damage: Damage) -> None:
        if self.damaged is None and damage.messages == 0:
            return  # strict reading refuses only what loses messages
        if self.damaged is None:
            raise BagError(
                f'damaged MCAP file: {damage} (`python -m mill_bag recover` keeps the rest)'
            )
        self.damaged.append(damage)
