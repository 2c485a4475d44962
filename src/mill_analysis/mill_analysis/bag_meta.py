"""The kinds of record a run gives, by name: what `run_scenario --record` notes in its bag.

Each job kind of mill_bringup names its kind of record (Job.RECORD); the runner writes that
name into the bag's metadata.yaml (custom_data, `KEY`), and `report` reads, summarises and
plots the bag through that kind (mill_analysis.report.kinds). A bag that names none (the
`recorder` node's, `ros2 bag record`'s) is told by its topics. ROS-free.
"""

from __future__ import annotations

import json
from collections.abc import Collection, Mapping, Sequence

from mill_bag.reader import Bag

from mill_common import topics

KEY = 'mill_record'  # the custom_data key of a bag's metadata.yaml
# custom_data key: samples missing per topic as the runner counted them (its summary's
# missing_samples, by absolute topic name), JSON (mill_bag.writer.counts_note); '{}' when
# none is missing; read back by Bag.noted_counts.
MISSING_SAMPLES = 'mill_missing_samples'
# custom_data key: the node each topic must come from (header.frame_id), by absolute topic
# name, JSON; `report` leaves out what the nodes drop, as the runner's record does.
OWNERS = 'mill_owners'
AXIS = 'axis'  # the three-axis job in lockstep: samples on the grid t = k T
AXIS_REALTIME = 'axis-realtime'  # the three-axis job on the drive's clock: its own stamps
FORCE = 'force'  # the cutting-force job of Rubio 2013: one sample per spindle revolution
NAMES = (AXIS, AXIS_REALTIME, FORCE)


def bag_notes(kind: str) -> dict[str, str]:
    """What a bag of this kind of record says of itself (its metadata's custom_data)."""
    if kind not in NAMES:
        raise ValueError(f'no kind of record {kind!r} (known: {", ".join(NAMES)})')
    return {KEY: kind}


def named(custom_data: Mapping[str, str]) -> str | None:
    """The kind of record a bag names in its custom_data, None if it names none."""
    return custom_data.get(KEY) or None


def owners_note(owners: Mapping[str, str], namespace: str) -> dict[str, str]:
    """The bag's note of the topics' owners (relative names, qualified in `namespace`)."""
    absolute = {topics.qualify(t, namespace): node for t, node in sorted(owners.items())}
    return {OWNERS: json.dumps(absolute)}


def owners(custom_data: Mapping[str, str], namespace: str) -> dict[str, str]:
    """The owners a bag notes, by relative topic name in its run's namespace ({}: none, or a
    note that cannot be read)."""
    try:
        noted = json.loads(custom_data.get(OWNERS, '{}'))
        pairs = [(str(t), str(node)) for t, node in noted.items()]
    except (ValueError, TypeError, AttributeError):
        return {}
    prefix = topics.qualify('', namespace)  # '/' or '/machine2/'
    return {name.removeprefix(prefix): node for name, node in pairs if name.startswith(prefix)}


def missing_ranges(have: Collection[int], n: int) -> list[tuple[int, int]]:
    """The samples 0 .. n − 1 not in `have`, as (first, last) of each run of them."""
    out: list[tuple[int, int]] = []
    start = None
    for k in range(n + 1):
        gone = k < n and k not in have
        if gone and start is None:
            start = k
        elif not gone and start is not None:
            out.append((start, k - 1))
            start = None
    return out


def format_ranges(ranges: Sequence[Sequence[int]], most: int = 6) -> str:
    """'k = 0–648, 700, 702–710' (the first `most` runs; how many more)."""
    parts = [f'{a}' if a == b else f'{a}–{b}' for a, b in ranges[:most]]
    more = len(ranges) - most
    return 'k = ' + ', '.join(parts) + (f' and {more} more runs' if more > 0 else '')


def loss_lines(
    missing: Mapping[str, int], gaps: Mapping[str, Sequence[Sequence[int]]] | None = None
) -> list[str]:
    """One WARNING line per topic that lacks samples in the record, with the samples it lacks
    where known (`gaps`: per topic, the runs of missing samples); none where no topic does
    (the runner's summary and `report` print these)."""
    gaps = gaps or {}
    return [
        f'WARNING: {t}: samples missing in the record: {n}'
        + (f' ({format_ranges(gaps[t])})' if gaps.get(t) else '')
        for t, n in missing.items()
        if n
    ]


def bag_counts(bag: Bag) -> dict[str, int]:
    """Messages per topic of a bag (from its metadata.yaml, else by reading it)."""
    try:
        info = bag.metadata['rosbag2_bagfile_information']  # type: ignore[index]
        return {
            t['topic_metadata']['name']: int(t.get('message_count', 0))
            for t in info['topics_with_message_count']
        }
    except (KeyError, TypeError):
        for _ in bag.read(topics=()):
            pass
        return dict(bag.counts)
