"""Writing a rosbag2 bag in MCAP storage, in chunks that survive a hard kill and a full disk.

    BAG/metadata.yaml    rosbag2_bagfile_information, version 9, as Jazzy writes it
    BAG/BAG_0.mcap       profile "ros2", one schema (ros2msg) per type, one channel per
                         topic with metadata offered_qos_profiles (YAML) and topic_type_hash;
                         messages CDR as they arrived, log time = the bag time, publish
                         time kept apart (a recorder stores the receive time there)

`BagWriter.flush()` closes the current MCAP chunk, hands it to the operating system
and rewrites metadata.yaml (atomically; it exists from the start), so a writer that
flushes every half second loses at most that much to a hard kill; `mill_bag.reader`
reads such a file up to its last complete chunk and `mill_bag.recover` completes it.
`close()` writes the MCAP summary, footer and the final metadata.yaml.

A write the operating system refuses (a full disk, above all) cuts the bag short
instead of leaving it damaged: the MCAP file is cut back to the end of its last
complete flush, and metadata.yaml describes what is in it and says why it ends there
(`custom_data: cut_short: <reason>`, a field rosbag2 keeps for such notes). Writing
that last metadata.yaml needs room on a disk that has none: the writer holds
RESERVE_NAME, a file of twice the size of metadata.yaml (at least 64 KiB), allocated
while there is room and deleted when the bag is closed or cut short. The same field
carries the writer's own notes for the bag's readers (`BagWriter(custom_data=...)`, e.g.
what kind of run a bag holds); `Bag.custom_data` reads them back, `recover` keeps them.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, cast

import yaml

from mill_bag.errors import BagError
from mill_bag.types import message_definition

ROSBAG2_VERSION = 9
COMPRESSIONS = ('zstd', 'lz4', 'none')
CUT_SHORT = 'cut_short'  # custom_data key: why the recording ended before it was closed
RESERVE_NAME = '.metadata_reserve'  # room kept for the last metadata.yaml (deleted at close)
RESERVE_MIN = 64 * 1024
FULL = (errno.ENOSPC, errno.EDQUOT)
MAX_TIME = (1 << 64) - 1  # MCAP times are uint64 ns


def os_reason(exc: OSError) -> str:
    """An OSError in words: 'no space left on device'."""
    text = exc.strerror or str(exc)
    return text[:1].lower() + text[1:]


class _FlushedFile:
    """The stream under the MCAP writer: bytes reach the file only at flush(), and a flush
    the OS refuses leaves the file as it was after the last complete one (never a partial
    record), so the file stays a readable MCAP prefix whatever happens."""

    def __init__(self, path: Path) -> None:
        self._fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        self._buf = bytearray()
        self.size = 0  # bytes in the file, all of complete flushes

    def write(self, data: bytes) -> int:
        self._buf += data
        return len(data)

    def tell(self) -> int:
        return self.size + len(self._buf)

    def flush(self) -> None:
        view = memoryview(self._buf)
        done = 0
        try:
            while done < len(view):
                done += os.write(self._fd, view[done:])
        except OSError:
            view.release()
            os.ftruncate(self._fd, self.size)  # back to the end of the last complete flush
            os.lseek(self._fd, self.size, os.SEEK_SET)
            raise
        view.release()
        self.size += len(self._buf)
        self._buf.clear()

    def fsync(self) -> None:
        os.fsync(self._fd)

    def close(self) -> None:
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1


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
    A write the OS refuses raises `BagCutShort` and leaves the bag cut short (`cut_short`
    says why); nothing is written after that.
    """

    def __init__(
        self,
        path: Path,
        compression: str = 'zstd',
        chunk_size: int = 1 << 20,
        custom_data: Mapping[str, str] | None = None,
    ) -> None:
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
        self.topics: dict[str, TopicInfo] = {}
        self._schemas: dict[str, int] = {}
        self.message_count = 0
        self.start_ns: int | None = None
        self.end_ns: int | None = None
        self.closed = False
        self.cut_short: str | None = None  # why writing stopped before close(), if it did
        # What the bag's writer says of it, for its readers: metadata.yaml's custom_data, the
        # place rosbag2 keeps such notes (`ros2 bag record --custom-data`).
        self.custom_data = {str(k): str(v) for k, v in (custom_data or {}).items()}
        self._reserved = 0
        try:
            self._file = _FlushedFile(self.path / self.file_name)
            kind = {
                'zstd': CompressionType.ZSTD,
                'lz4': CompressionType.LZ4,
                'none': CompressionType.NONE,
            }[compression]
            # The mcap Writer needs only write() and tell() of its stream, which we have.
            stream = cast(IO[Any], self._file)
            self._mcap = Writer(stream, chunk_size=chunk_size, compression=kind)
            self._mcap.start(profile='ros2', library=f'mill recorder ({mcap_library()})')
            self._file.flush()
            self._flushed = self.metadata()  # what the file holds after the last flush
            self.write_metadata()
        except OSError as exc:
            self._remove_started_bag()
            raise BagError(f'cannot create the bag {self.path}: {os_reason(exc)}') from None

    def _remove_started_bag(self) -> None:
        if getattr(self, '_file', None) is not None:
            self._file.close()
        for name in (self.file_name, RESERVE_NAME, 'metadata.yaml', 'metadata.yaml.tmp'):
            (self.path / name).unlink(missing_ok=True)
        self.path.rmdir()

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
        """Add one message. BagError (the bag unchanged) for times MCAP cannot hold: mcap
        would fail halfway through the record and leave the chunk unreadable."""
        if self.closed:
            raise BagError(f'the bag {self.path} is closed' + self._why())
        if not (0 <= log_time <= MAX_TIME and 0 <= publish_time <= MAX_TIME):
            raise BagError(
                f'{topic.name}: log time {log_time} / publish time {publish_time} ns is no '
                'MCAP time (0 to 2^64 - 1)'
            )
        self._mcap.add_message(topic.channel_id, log_time, data, publish_time, topic.count)
        topic.count += 1
        self.message_count += 1
        if self.start_ns is None or log_time < self.start_ns:
            self.start_ns = log_time
        if self.end_ns is None or log_time > self.end_ns:
            self.end_ns = log_time

    def _why(self) -> str:
        return f' (cut short: {self.cut_short})' if self.cut_short else ''

    def flush(self) -> None:
        """Close the current chunk, hand it to the OS and refresh metadata.yaml."""
        if self.closed:
            raise BagError(f'the bag {self.path} is closed' + self._why())
        try:
            self._mcap.flush()
        except OSError as exc:
            self._cut(exc)
        self._flushed = self.metadata()
        try:
            self.write_metadata()
        except OSError as exc:
            self._cut(exc)

    def metadata(self) -> dict:
        return bag_metadata(
            [self.file_name],
            list(self.topics.values()),
            self.start_ns or 0,
            (self.end_ns or 0) - (self.start_ns or 0),
            self.custom_data,
        )

    def write_metadata(self) -> None:
        """metadata.yaml of what was flushed; the reserve grows with it first."""
        text = dump_yaml(self._flushed) + '\n'
        self._reserve(max(RESERVE_MIN, 2 * len(text.encode())))
        write_metadata_file(self.path, self._flushed, text)

    def _reserve(self, size: int) -> None:
        if size <= self._reserved:
            return
        fd = os.open(self.path / RESERVE_NAME, os.O_WRONLY | os.O_CREAT, 0o644)
        try:
            try:
                os.posix_fallocate(fd, 0, size)
            except OSError as exc:
                if exc.errno not in (errno.EOPNOTSUPP, errno.EINVAL):
                    raise
                os.pwrite(fd, bytes(size), 0)  # a file system without fallocate
        finally:
            os.close(fd)
        self._reserved = size

    def _cut(self, exc: OSError) -> None:
        """Stop at the last complete flush (see `abort`); raise BagCutShort."""
        self.abort(os_reason(exc))
        info = self._flushed['rosbag2_bagfile_information']
        assert self.cut_short is not None
        raise BagCutShort(self.path, self.cut_short, info['message_count'])

    def abort(self, reason: str) -> None:
        """End the bag at its last complete flush, for `reason`: what was written since is
        dropped (it may be half a record), the reserve freed, and metadata.yaml describes what
        the file holds and says why it ends there. The file has no footer: readers read it,
        `recover` completes it."""
        if self.closed:
            return
        self.closed = True
        self.cut_short = reason
        self._file.close()
        (self.path / RESERVE_NAME).unlink(missing_ok=True)
        self._reserved = 0
        info = self._flushed['rosbag2_bagfile_information']
        info['custom_data'] = {**self.custom_data, CUT_SHORT: self.cut_short}
        self.message_count = info['message_count']  # what the file holds
        # If even this fails, the metadata of the last flush stays: the file still reads.
        with contextlib.suppress(OSError):
            write_metadata_file(self.path, self._flushed)

    def close(self) -> None:
        if self.closed:
            return
        info = self.metadata()
        try:
            self._mcap.add_metadata(
                'rosbag2', {'serialized_metadata': dump_yaml(info['rosbag2_bagfile_information'])}
            )
            self._mcap.finish()
            self._file.flush()
            self._file.fsync()
        except OSError as exc:
            self._cut(exc)
        self.closed = True
        self._file.close()
        (self.path / RESERVE_NAME).unlink(missing_ok=True)
        self._flushed = info
        write_metadata_file(self.path, info)

    @property
    def size_bytes(self) -> int:
        return (self.path / self.file_name).stat().st_size


class BagCutShort(BagError):
    """The OS refused a write (a full disk): the bag ends at its last complete flush."""

    def __init__(self, path: Path, reason: str, messages: int) -> None:
        super().__init__(
            f'{reason}: the bag {path} is cut short after {messages} messages '
            f'(`python -m mill_bag recover {path}` completes it once there is room)'
        )
        self.path = path
        self.reason = reason
        self.messages = messages


def counts_note(counts: Mapping[str, int]) -> str:
    """Per-topic counts as one custom_data note (string -> string): JSON of the topics with
    a non-zero count, by name (read back by `Bag.noted_counts`)."""
    return json.dumps({t: int(n) for t, n in sorted(counts.items()) if n})


def mcap_library() -> str:
    from mcap.writer import LIBRARY_IDENTIFIER

    return LIBRARY_IDENTIFIER


class _Dumper(getattr(yaml, 'CSafeDumper', yaml.SafeDumper)):  # type: ignore[misc]
    """libyaml when there (10x faster); no anchors and aliases, which readers refuse
    (mill_common.yaml_files), even where one object appears twice."""

    def ignore_aliases(self, data: Any) -> bool:
        return True


_DUMPER = _Dumper


def dump_yaml(value: Any) -> str:
    return yaml.dump(value, Dumper=_DUMPER, default_flow_style=False, sort_keys=False).strip()


def bag_metadata(
    files: Sequence[str],
    topics: Sequence[TopicInfo],
    start_ns: int,
    duration_ns: int,
    custom_data: Mapping[str, str] | None = None,
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
            'custom_data': dict(custom_data or {}),
            'ros_distro': 'jazzy',
        }
    }


def write_metadata_file(bag_dir: Path, metadata: dict, text: str | None = None) -> None:
    """metadata.yaml, replaced atomically (a reader never sees half a file); a failed write
    leaves the previous one and no temporary file."""
    tmp = bag_dir / 'metadata.yaml.tmp'
    try:
        tmp.write_text(text if text is not None else dump_yaml(metadata) + '\n')
    except OSError:
        tmp.unlink(missing_ok=True)
        raise
    tmp.replace(bag_dir / 'metadata.yaml')
