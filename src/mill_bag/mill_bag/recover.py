"""Recovering a killed recording: its MCAP files rewritten as complete ones.

A recording killed hard (SIGKILL, power loss) leaves MCAP files without summary
and footer, which most readers refuse (`mill_bag.reader` reads them up to the last
complete chunk). `recover` writes every message of the complete records into a new
file with the same channels (QoS, type hash), keeps the original as
NAME.mcap.truncated and rebuilds metadata.yaml from the data. It needs room for the
new file; on a full disk it removes what it began and leaves the bag as it was.

    python -m mill_bag recover BAG
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import yaml

from mill_bag.errors import BagError
from mill_bag.reader import Bag, open_bag
from mill_bag.types import message_definition
from mill_bag.writer import (
    RESERVE_NAME,
    TopicInfo,
    bag_metadata,
    dump_yaml,
    mcap_library,
    os_reason,
)


def recover(path: str | Path) -> tuple[int, int]:
    """Rewrite the truncated MCAP files of a killed recording as complete ones.

    Every message of the complete records is kept, with its channel metadata (QoS,
    type hash); metadata.yaml is rebuilt from the data (keeping a cut-short note). The
    original file is kept next to it as NAME.mcap.truncated. Returns (messages kept,
    files rewritten). Nothing changes until every new file is written: a failure (a full
    disk) removes what was begun and raises BagError with the bag as it was.
    """
    bag = open_bag(path)
    if bag.storage != 'mcap':
        raise BagError(f'{bag.path}: only MCAP bags can be recovered')
    rows = list(bag.read())
    if not bag.truncated:
        return len(rows), 0
    written: list[Path] = []  # every file begun, removed again if anything fails
    try:
        done = [_rewrite(src, bag, written) for src in bag.truncated]
        metadata = None
        if bag.path.is_dir():
            metadata = bag.path / 'metadata.yaml.recovering'
            written.append(metadata)
            topics = [info for d in done for info in d.topics]
            start = min((d.start for d in done if d.start is not None), default=0)
            end = max((d.end for d in done if d.end is not None), default=0)
            # The writer's notes (a cut-short reason, what the bag holds) stay.
            meta = bag_metadata(
                [d.src.name for d in done], topics, start, end - start, bag.custom_data
            )
            metadata.write_text(dump_yaml(meta) + '\n')
    except OSError as exc:
        for begun in written:
            begun.unlink(missing_ok=True)
        needed = sum(src.stat().st_size for src in bag.truncated) / 1e6
        raise BagError(
            f'cannot recover {bag.path}: {os_reason(exc)} (the complete copy needs about '
            f'{needed:.1f} MB next to it); the bag is unchanged'
        ) from None
    # Only renames from here: they need no room.
    for d in done:
        d.src.rename(d.src.with_name(d.src.name + '.truncated'))
        d.tmp.rename(d.src)
    if metadata is not None:
        metadata.replace(bag.path / 'metadata.yaml')
        (bag.path / RESERVE_NAME).unlink(missing_ok=True)
    return sum(info.count for d in done for info in d.topics), len(done)


@dataclass
class _Rewritten:
    src: Path  # the truncated file
    tmp: Path  # its complete copy, renamed to src once every copy is written
    topics: list[TopicInfo]  # with their message counts
    start: int | None  # first and last log time
    end: int | None


def _rewrite(src: Path, bag: Bag, written: list[Path]) -> _Rewritten:
    """Write the complete records of one truncated file into SRC.mcap.recovering."""
    from mcap.writer import CompressionType, Writer

    tmp = src.with_suffix('.mcap.recovering')
    written.append(tmp)
    with open(tmp, 'wb') as out:
        writer = Writer(out, compression=CompressionType.ZSTD)
        writer.start(profile='ros2', library=f'mill recover ({mcap_library()})')
        sub = open_bag(src) if bag.path.is_dir() else bag
        infos: dict[str, TopicInfo] = {}
        schemas: dict[str, int] = {}
        start = end = None
        for topic, msgtype, log_time, publish_time, data in sub.read():
            info = infos.get(topic)
            if info is None:
                msgdef, rihs01 = message_definition(msgtype)
                if msgtype not in schemas:
                    schemas[msgtype] = writer.register_schema(msgtype, 'ros2msg', msgdef.encode())
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
        out.flush()
        os.fsync(out.fileno())
    return _Rewritten(src, tmp, list(infos.values()), start, end)
