"""The kinds of record a run gives, by name: what `run_scenario --record` notes in its bag.

Each job kind of mill_bringup names its kind of record (Job.RECORD); the runner writes that
name into the bag's metadata.yaml (custom_data, `KEY`), and `report` reads, summarises and
plots the bag through that kind (mill_analysis.report.kinds). A bag that names none (the
`recorder` node's, `ros2 bag record`'s) is told by its topics. ROS-free.
"""

from __future__ import annotations

from collections.abc import Mapping

KEY = 'mill_record'  # the custom_data key of a bag's metadata.yaml
# custom_data key: samples missing per topic as the runner counted them (its summary's
# missing_samples, by absolute topic name), JSON (mill_bag.writer.counts_note); '{}' when
# none is missing; read back by Bag.noted_counts.
MISSING_SAMPLES = 'mill_missing_samples'
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


def loss_lines(missing: Mapping[str, int]) -> list[str]:
    """One WARNING line per topic that lacks samples in the record; none where no topic does
    (the runner's summary and `report` print these)."""
    return [f'WARNING: {t}: samples missing in the record: {n}' for t, n in missing.items() if n]
