"""Reading a rosbag2 bag (MCAP or sqlite3 storage) or a bare .mcap file, by topic and type.

`open_bag(path)` gives a `Bag`; `Bag.read()` yields (topic, type, log_time,
publish_time, data) with the data still CDR, so a reader decodes only what it
needs (`mill_bag.types.decode`). Only topic names and types are needed, so bags
of `ros2 bag record` (MCAP or sqlite3 storage) read like ours.

An MCAP file without footer (the recording was killed) is read up to its last
complete record, and `Bag.truncated` lists it: the writer flushes whole chunks, so
that is every message up to the last flush. `mill_bag.recover` rewrites it. A bag the
writer cut short (a full disk) says why in metadata.yaml: `Bag.cut_short`. A damaged file
(flipped bytes) raises BagError in one line saying where and how much is lost;
`read(damaged=[...])` reads around the damage instead (mill_bag.mcap_read), as `recover` does.
"""

from __future__ import annotations

import json
from collections.abc import Collection, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import yaml
from mill_common.yaml_files import read_yaml

from mill_bag.errors import BagError
from mill_bag.mcap_read import Damage, McapFile, Row
from mill_bag.writer import CUT_SHORT, dump_yaml


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

    def read(
        self, topics: Collection[str] | None = None, damaged: list[Damage] | None = None
    ) -> Iterator[Row]:
        """Messages of `topics` (None: all). A damaged MCAP file raises BagError, in one line
        on where; with a `damaged` list, its damaged parts are noted there and the rest is
        read (mill_bag.mcap_read)."""
        self.counts.clear()
        self.truncated.clear()
        for path in self.files:
            if self.storage == 'mcap':
                yield from self._read_mcap(path, topics, damaged)
            else:
                yield from self._read_rosbags(topics)
                break

    def _read_mcap(
        self, path: Path, topics: Collection[str] | None, damaged: list[Damage] | None
    ) -> Iterator[Row]:
        hints = self._channel_hints() if damaged is not None and len(self.files) == 1 else None
        mcap = McapFile(path, self, topics, damaged, hints)
        if not mcap.complete:
            self.truncated.append(path)
        try:
            yield from mcap.rows()
        except BagError:
            raise  # McapFile's own: with the file and where
        except Exception as exc:  # mcap, zstandard, lz4 and struct raise many types
            raise BagError(f'{path}: damaged MCAP file ({exc or type(exc).__name__})') from None

    def _channel_hints(self) -> dict[int, tuple[str, str, str]]:
        """Channel id -> (topic, type, QoS YAML) as mill_bag's writer numbers its channels: its
        topics in metadata.yaml's order, from 1. Recovers the messages of a killed recording
        whose channel definitions were in a damaged chunk (mill_bag.mcap_read)."""
        info = (self.metadata or {}).get('rosbag2_bagfile_information') or {}
        out = {}
        try:
            for i, entry in enumerate(info.get('topics_with_message_count') or [], 1):
                t = entry['topic_metadata']
                out[i] = (
                    str(t['name']),
                    str(t['type']),
                    dump_yaml(t.get('offered_qos_profiles') or []),
                )
        except (KeyError, TypeError, AttributeError):
            return {}
        return out

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
            meta = read_yaml(meta_path)
            info = meta['rosbag2_bagfile_information']
            storage = info.get('storage_identifier', 'mcap')
            names = list(info.get('relative_file_paths') or [])
        except (yaml.YAMLError, UnicodeDecodeError, KeyError, TypeError, AttributeError):
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
