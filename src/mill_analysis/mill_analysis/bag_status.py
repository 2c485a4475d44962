"""What a run's /diagnostics say about its job: where it started and ended, the plant's
last status. Read from the decoded DiagnosticArray messages of a bag (`bag_run`). ROS-free.
"""

from __future__ import annotations

from typing import Any

from mill_common import topics


def status_values(status: Any) -> dict[str, str]:
    return {kv.key: kv.value for kv in status.values}


def job_end(statuses: list[Any]) -> tuple[float | None, str]:
    """end_time of the trajectory's "done" status, else of its first status: with a feed
    override only the "done" one knows where the job ended."""
    found = None
    for array in statuses:
        for status in array.status:
            if topics.part_of(status.name) == topics.JOB_STATUS:
                values = status_values(status)
                if 'end_time' not in values:
                    continue
                if values.get('state') == 'done':
                    return float(values['end_time']), 'job status on /diagnostics'
                if found is None:
                    found = float(values['end_time'])
    return found, 'job status on /diagnostics' if found is not None else ''


def plant_status(statuses: list[Any]) -> dict[str, str]:
    for array in reversed(statuses):
        for status in array.status:
            if topics.part_of(status.name) in topics.DRIVE_STATUSES:
                return status_values(status) | {'message': status.message}
    return {}


def job_start(statuses: list[Any]) -> int | None:
    """The start stamp of a realtime job, from the trajectory's status (None: lockstep)."""
    for array in reversed(statuses):
        for status in array.status:
            if topics.part_of(status.name) == topics.JOB_STATUS:
                values = status_values(status)
                if 'start_stamp_ns' in values:
                    return int(values['start_stamp_ns'])
    return None


def job_approach(statuses: list[Any]) -> float:
    """How long a realtime job's approach to its path's start lasted [s], from the
    trajectory's status (`approach_s`; 0: none, or a lockstep job)."""
    for array in reversed(statuses):
        for status in array.status:
            if topics.part_of(status.name) == topics.JOB_STATUS:
                values = status_values(status)
                if 'approach_s' in values:
                    return float(values['approach_s'])
    return 0.0
