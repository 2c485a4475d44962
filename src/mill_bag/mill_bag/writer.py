"""Writing a rosbag2 bag in MCAP storage, in chunks that survive a hard kill.

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
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from mill_bag.errors import BagError
from mill_bag.types import message_definition

ROSBAG2_VERSION = 9
COMPRESSIONS = ('zstd', 'lz4', 'none')


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
        self._mcap.start(profile='ros2', library=f'mill recorder ({mcap_library()})')
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


def mcap_library() -> str:
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
