"""Recovering a killed recording or a damaged bag: its MCAP files rewritten as complete ones.

A recording killed hard (SIGKILL, power loss) leaves MCAP files without summary
and footer, which most readers refuse (`mill_bag.reader` reads them up to the last
complete chunk). A file with flipped bytes has damaged chunks, which readers refuse
whole. `recover` writes every message it can read into a new file with the same channels
(QoS, type hash): all of the complete records of a killed recording, every chunk but the
damaged ones of a damaged file (mill_bag.mcap_read says what each damaged part cost). It
keeps the original as NAME.mcap.truncated (NAME.mcap.damaged) and rebuilds metadata.yaml
from the data, with a `damaged` note if anything was lost. It needs room for the new file;
on a full disk it removes what it began and leaves the bag as it was.

    python -m mill_bag recover BAG
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml
from mill_common.yaml_files import parse_yaml

from mill_bag.errors import BagError
from mill_bag.mcap_read import Damage
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

DAMAGED = 'damaged'  # custom_data note of a recovered bag: what its damaged parts cost


def recover(path: str | Path, damaged: list[Damage] | None = None) -> tuple[int, int]:
    """Rewrite the truncated or damaged MCAP files of a bag as complete ones.

    Every message that reads is kept, with its channel metadata (QoS, type hash); each
    damaged part is appended to `damaged`. metadata.yaml is rebuilt from the data (keeping
    the writer's notes). The original file is kept next to it as NAME.mcap.truncated
    (.damaged). Returns (messages kept, files rewritten). Nothing changes until every new
    file is written: a failure (a full disk) removes what was begun and raises BagError
    with the bag as it was.
    """
    bag = open_bag(path)
    if bag.storage != 'mcap':
        raise BagError(f'{bag.path}: only MCAP bags can be recovered')
    found: list[Damage] = []
    kept = sum(1 for _ in bag.read(damaged=found))
    if damaged is not None:
        damaged.extend(found)
    broken = {d.path for d in found}
    todo = [f for f in bag.files if f in bag.truncated or f in broken]
    if not todo:
        return kept, 0
    written: list[Path] = []  # every file begun, removed again if anything fails
    try:
        done = [_rewrite(src, bag, written) for src in todo]
        metadata = None
        if bag.path.is_dir():
            metadata = bag.path / 'metadata.yaml.recovering'
            written.append(metadata)
            topics = [info for d in done for info in d.topics]
            start = min((d.start for d in done if d.start is not None), default=0)
            end = max((d.end for d in done if d.end is not None), default=0)
            # The writer's notes (a cut-short reason, what the bag holds) stay.
            notes = bag.custom_data | ({DAMAGED: describe_loss(found)} if found else {})
            meta = bag_metadata([d.src.name for d in done], topics, start, end - start, notes)
            metadata.write_text(dump_yaml(meta) + '\n')
    except OSError as exc:
        for begun in written:
            begun.unlink(missing_ok=True)
        needed = sum(src.stat().st_size for src in todo) / 1e6
        raise BagError(
            f'cannot recover {bag.path}: {os_reason(exc)} (the complete copy needs about '
            f'{needed:.1f} MB next to it); the bag is unchanged'
        ) from None
    # Only renames from here: they need no room.
    for d in done:
        suffix = '.damaged' if d.src in broken else '.truncated'
        d.src.rename(d.src.with_name(d.src.name + suffix))
        d.tmp.rename(d.src)
    if metadata is not None:
        metadata.replace(bag.path / 'metadata.yaml')
        (bag.path / RESERVE_NAME).unlink(missing_ok=True)
    return sum(info.count for d in done for info in d.topics), len(done)


def describe_loss(damaged: list[Damage]) -> str:
    """'2 damaged parts, 300 messages lost' (', and more' where a part's count is unknown)."""
    lost = sum(d.messages or 0 for d in damaged)
    more = ', and more' if any(d.messages is None for d in damaged) else ''
    return f'{len(damaged)} damaged part(s), {lost} messages lost{more}'


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
        sub = bag if len(bag.files) == 1 else open_bag(src)  # a bag: its channel hints too
        infos: dict[str, TopicInfo] = {}
        schemas: dict[str, int] = {}
        start = end = None
        for topic, msgtype, log_time, publish_time, data in sub.read(damaged=[]):
            info = infos.get(topic)
            if info is None:
                msgdef, rihs01 = message_definition(msgtype)
                if msgtype not in schemas:
                    schemas[msgtype] = writer.register_schema(msgtype, 'ros2msg', msgdef.encode())
                qos_text = sub.qos.get(topic, '')
                qos = _qos(qos_text)
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


def _qos(text: str) -> Any:
    """The QoS profiles a channel offered (its metadata's YAML); [] if it has none or they
    cannot be read safely (mill_common.yaml_files): the messages are kept all the same."""
    if not text:
        return []
    try:
        return parse_yaml(text)
    except yaml.YAMLError:
        return []
