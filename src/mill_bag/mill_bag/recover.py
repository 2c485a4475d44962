"""Recovering a killed recording: its MCAP files rewritten as complete ones.

A recording killed hard (SIGKILL, power loss) leaves MCAP files without summary
and footer, which most readers refuse (`mill_bag.reader` reads them up to the last
complete chunk). `recover` writes every message of the complete records into a new
file with the same channels (QoS, type hash), keeps the original as
NAME.mcap.truncated and rebuilds metadata.yaml from the data.

    python -m mill_bag recover BAG
"""

from __future__ import annotations

from pathlib import Path

import yaml

from mill_bag.errors import BagError
from mill_bag.reader import open_bag
from mill_bag.types import message_definition
from mill_bag.writer import TopicInfo, bag_metadata, mcap_library, write_metadata_file


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
            writer.start(profile='ros2', library=f'mill recover ({mcap_library()})')
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
