"""The values of a drive's status `<drive>: realtime` that the runner reads, declared once.
ROS-free.

`<drive>` is the node name of the driver, the one in its states' `header.frame_id` (the
scenario's plant node, `plant` by default; the controllers' `plant_node`); `realtime` is the
part of the status (mill_common.topics.DRIVE_STATUSES). A drive's status of another name is
not read: the runner says so once, at the end of the run (`misnamed`).

The runner reads the per-axis values as `<axis>.<key>` (`x.stopped`) and the drive's own as
`<key>`. Every key is optional: one the drive does not send counts as 0 or unknown (NaN,
''), and the runner then falls back on what it measured itself (the commands' timing as it
received them). docs/hardware-driver.md lists every key below; a test checks that it does.
"""

from __future__ import annotations

from collections.abc import Iterable

PART = 'realtime'  # mill_common.topics.DRIVE_STATUSES[1]

# -- per axis: `<axis>.<key>` --------------------------------------------------------------------
STOPS = 'stops'
STOPPED = 'stopped'
INVALID_COMMANDS = 'invalid_commands'
FAULT = 'fault'
LATE_FRACTION = 'late_fraction'
LONGEST_LATE_RUN = 'longest_late_run'
LATENCY_MEDIAN_MS = 'latency_median_ms'
LATENCY_P99_MS = 'latency_p99_ms'
LATENCY_MAX_MS = 'latency_max_ms'

PER_AXIS: dict[str, str] = {
    STOPS: 'times the drive has stopped the axis so far (each new one: a `stopped` event, '
    'which fails a realtime job)',
    STOPPED: "why the axis is stopped now (braked and latched until re-armed), '' while it is "
    'not: a job does not start on an axis stopped so (run_scenario --rearm releases it)',
    INVALID_COMMANDS: 'brake requests (NaN commands) taken so far: the first, a `braked` event',
    FAULT: "what the machine reports wrong with the axis, '' when nothing: a `fault` event",
    LATE_FRACTION: 'fraction of its ticks without a fresh command',
    LONGEST_LATE_RUN: 'most such ticks in a row',
    LATENCY_MEDIAN_MS: 'state -> command latency, median [ms]',
    LATENCY_P99_MS: '... 99th percentile [ms]',
    LATENCY_MAX_MS: '... maximum [ms]',
}
# The drive's figures of each axis in the run's summary (mill_analysis.summary.DriveFigures).
FIGURES = (LATE_FRACTION, LONGEST_LATE_RUN, LATENCY_MEDIAN_MS, LATENCY_P99_MS, LATENCY_MAX_MS)

# -- the drive's own: `<key>` --------------------------------------------------------------------
OVERRUNS = 'overruns'
ACTIVE_TICKS = 'active_ticks'
STALLS = 'stalls'
LONGEST_STALL_MS = 'longest_stall_ms'
LONGEST_STALL = 'longest_stall'
STALL_REPORT_MS = 'stall_report_ms'

DRIVE: dict[str, str] = {
    OVERRUNS: 'ticks more than half a period late so far',
    ACTIVE_TICKS: 'ticks while active (the basis of overruns)',
    STALLS: 'its own stalls so far: ticks that woke more than stall_report late (monotonic)',
    LONGEST_STALL_MS: 'the longest of them [ms]',
    LONGEST_STALL: 'that stall said in one line (which process, how long, when)',
    STALL_REPORT_MS: 'the threshold of a stall [ms]',
}


def axis_key(axis: str, key: str) -> str:
    """`x.stopped`."""
    return f'{axis}.{key}'


def stopped(values: dict[str, str], axes: Iterable[str]) -> dict[str, str]:
    """The axes a drive's status says are stopped now (latched), with the reason of each."""
    out = {}
    for axis in axes:
        reason = values.get(axis_key(axis, STOPPED), '')
        if reason:
            out[axis] = reason
    return out


def misnamed(names: Iterable[str], drive: str) -> str:
    """What to say once when a drive `drive` (its node name) sent statuses, but none named
    `<drive>: realtime`; '' when it sent one, or nothing at all. names: the names of the
    statuses heard."""
    expected = f'{drive}: {PART}'
    own = sorted({n for n in names if n.partition(': ')[0] == drive})
    if not own or expected in own:
        return ''
    return (
        f'the drive {drive} sent statuses named {", ".join(own)} but none named {expected!r}: '
        "the runner read none of its figures nor its axes' stops from them "
        '(docs/hardware-driver.md, "What the runner reads")'
    )
