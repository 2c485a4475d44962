"""What an MCAP file's indexes say, read without trusting them. ROS-free.

MCAP repeats what a reader needs to find its way: after each chunk a message index record per
channel (the log time and offset of each of its messages in the chunk), and after DataEnd a
summary (schemas, channels, one chunk index record per chunk: where it starts, its time span,
where its message indexes are). `mill_bag.mcap_read` reads the data section itself and turns
to these only where it is damaged: to find the next chunk, the definition of a channel, and
how many messages a damaged part held. Every function here checks what it reads and returns
None (or an empty `Summary`) for what does not hold together.
"""

from __future__ import annotations

import io
import struct
from dataclasses import dataclass, field
from typing import Any

MCAP_MAGIC = b'\x89MCAP0\r\n'
FOOTER, SCHEMA, CHANNEL, MESSAGE, CHUNK, MESSAGE_INDEX, CHUNK_INDEX = 2, 3, 4, 5, 6, 7, 8
DATA_END = 0x0F
FRAME = struct.Struct('<BQ')  # every record: opcode, length of its body
_INDEX = struct.Struct('<HI')  # a message index: channel, length of its 16-byte entries
FOOTER_SIZE = 9 + 20


def read_record(record: type, buf: bytes, start: int, stop: int) -> Any:
    """One record (an mcap.records class) from its body, buf[start:stop]."""
    from mcap.data_stream import ReadDataStream

    return record.read(ReadDataStream(io.BytesIO(buf[start:stop])))  # type: ignore[attr-defined]


def index_ok(data: bytes, pos: int) -> bool:
    """A message index record at pos: its length is that of its entries, 16 bytes each."""
    if pos + 15 > len(data) or data[pos] != MESSAGE_INDEX:
        return False
    length = FRAME.unpack_from(data, pos)[1]
    entries = _INDEX.unpack_from(data, pos + 9)[1]
    return length == 6 + entries and entries % 16 == 0 and pos + 9 + length <= len(data)


def index_end(data: bytes, pos: int) -> int:
    """Where a message index at pos ends by its entries length, whatever its frame says (0:
    no whole number of entries)."""
    if pos + 15 > len(data):
        return 0
    entries = _INDEX.unpack_from(data, pos + 9)[1]
    return pos + 15 + entries if entries % 16 == 0 else 0


def index_times(data: bytes, offsets: list[int]) -> list[int] | None:
    """Log times of the message index records at `offsets`; None if one is damaged."""
    from mcap.records import MessageIndex

    times: list[int] = []
    for pos in offsets:
        if not index_ok(data, pos):
            return None
        stop = pos + 9 + FRAME.unpack_from(data, pos)[1]
        times += [t for t, _ in read_record(MessageIndex, data, pos + 9, stop).records]
    return times


def following_times(data: bytes, pos: int, complete: bool) -> list[int] | None:
    """Log times of the message index records from pos on (those of the chunk before pos);
    None if there are none, or what follows them is no chunk, no DataEnd and not the end of
    a killed recording (then one of them may be damaged)."""
    offsets = []
    while index_ok(data, pos):
        offsets.append(pos)
        pos += 9 + FRAME.unpack_from(data, pos)[1]
    if pos + 9 <= len(data):
        op, length = FRAME.unpack_from(data, pos)
        follows = op in (CHUNK, DATA_END) and pos + 9 + length <= len(data)
    else:
        follows = pos == len(data) and not complete
    return index_times(data, offsets) if offsets and follows else None


@dataclass
class Summary:
    """The summary section: channels (mcap Channel) and schema names by id, chunk indexes
    (mcap ChunkIndex), where DataEnd is. Empty where a file has none or it does not read."""

    channels: dict[int, Any] = field(default_factory=dict)
    schemas: dict[int, str] = field(default_factory=dict)
    chunks: list[Any] = field(default_factory=list)
    data_end: int | None = None


def read_summary(data: bytes) -> Summary:
    from mcap.records import Channel, ChunkIndex, Schema

    footer = len(data) - len(MCAP_MAGIC) - FOOTER_SIZE
    if footer < len(MCAP_MAGIC) or not data.endswith(MCAP_MAGIC) or data[footer] != FOOTER:
        return Summary()
    out = Summary()
    try:
        (pos,) = struct.unpack_from('<Q', data, footer + 9)
        out.data_end = (pos or footer) - 13
        while pos and pos < footer:
            op, length = FRAME.unpack_from(data, pos)
            start, pos = pos + 9, pos + 9 + length
            if op == SCHEMA:
                schema = read_record(Schema, data, start, pos)
                out.schemas[schema.id] = schema.name
            elif op == CHANNEL:
                channel = read_record(Channel, data, start, pos)
                out.channels[channel.id] = channel
            elif op == CHUNK_INDEX:
                out.chunks.append(read_record(ChunkIndex, data, start, pos))
    except Exception:
        return Summary()
    return out if data[out.data_end] == DATA_END else Summary()
