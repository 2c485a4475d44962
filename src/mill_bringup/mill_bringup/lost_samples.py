"""Samples a killed node took with it, told apart from samples the record lost.

A node killed (SIGKILL) while it sends a sample may have handed it to some readers and not
to others, and DDS cannot resend anything for a writer that is gone. With --respawn the
graph goes on from there: the controller acted on the estimate, the plant moved, and the
runner's record lacks that one sample. One sample per restart of the topic's sender is
that case and is reported as such; any other gap is a fault of the run.
"""

from __future__ import annotations

from collections.abc import Mapping


def split_lost(
    missing: Mapping[str, int], owners: Mapping[str, str], restarts: Mapping[str, int]
) -> tuple[dict[str, int], dict[str, int]]:
    """(still missing, lost with a killed sender) per topic.

    missing: samples missing per topic; owners: the node that sends each topic; restarts:
    how often each node was started again after it died.
    """
    still: dict[str, int] = {}
    lost: dict[str, int] = {}
    for topic, count in missing.items():
        excused = min(count, restarts.get(owners.get(topic, ''), 0))
        if excused:
            lost[topic] = excused
        if count > excused:
            still[topic] = count - excused
    return still, lost
