"""What a run gives: RunResult (figures of the run and of its job) and its text.

A run ends in one `Outcome` (run_scenario's exit codes, README "A real machine"), typed from
its ending (jobs.base.Ending: the failure that ended it, if any) and its record: interrupted
(Ctrl-C, SIGTERM), 130; the start refused (an axis the drive holds stopped), 2; `failures`
(a trip, a stop or a brake the job counts as a failure, a drive gone silent, a node that
died, a run that could not go on): the job failed, 1; else not `intact` (a sample missing
from the record or the bag, a foreign message or publisher): the job went well but the
runner's record of it is incomplete, 3; else good, 0. Every ending writes summary.json with
its `outcome` and `exit_code` (`write_summary`, the one place), a run that ended before it
had a result (`ended`) included.
"""

from __future__ import annotations

import enum
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mill_analysis.events import INTERRUPTED, REFUSED, Event
from mill_analysis.node_intake import drop_lines
from mill_analysis.summary import Summary
from mill_bag.intake import describe as describe_drops

from mill_analysis import bag_meta

GOOD = 0  # the job went well and the record is complete
JOB_FAILED = 1  # a trip, a stop, a brake, a drive gone silent, a node that died
START_REFUSED = 2  # the job did not start (an axis the drive holds stopped); 2 is usage too
RECORD_INCOMPLETE = 3  # the job went well, but the runner's record of it lacks something
INTERRUPTED_CODE = 130  # Ctrl-C or SIGTERM


class Outcome(enum.Enum):
    """How a run ended, each with run_scenario's exit code."""

    GOOD = 'good'
    RECORD_INCOMPLETE = 'record_incomplete'
    FAILED = 'failed'
    REFUSED = 'refused'
    INTERRUPTED = 'interrupted'

    @property
    def exit_code(self) -> int:
        return EXIT_CODES[self]


EXIT_CODES = {
    Outcome.GOOD: GOOD,
    Outcome.RECORD_INCOMPLETE: RECORD_INCOMPLETE,
    Outcome.FAILED: JOB_FAILED,
    Outcome.REFUSED: START_REFUSED,
    Outcome.INTERRUPTED: INTERRUPTED_CODE,
}


@dataclass
class RunResult:
    scenario: str
    kind: str
    samples: int
    sim_time: float
    wall_time: float
    real_time_factor: float
    steps_per_second: float
    cpu_ms_per_step: float
    peak_rss_mb: dict[str, float]
    cpu_ms_per_step_by_process: dict[str, float]
    peak_pss_mb: float  # graph + runner, sampled once a second (RSS counts libraries per process)
    domain_id: str
    missing_samples: dict[str, int]  # per topic, not counting lost_with_restarts
    summary: Summary  # the job's own figures and events (jobs.base.Job.summary)
    problems: list[str] = field(default_factory=list)  # WARN/ERROR heard on /diagnostics
    foreign: dict[str, int] = field(default_factory=dict)  # messages left out per topic
    # ... per topic and reason: (messages, the first one's reason) (Job.dropped)
    dropped: dict[str, list[tuple[int, str]]] = field(default_factory=dict)
    # per topic missing samples, the runs (first, last) of them
    missing_ranges: dict[str, list[tuple[int, int]]] = field(default_factory=dict)
    # per topic, messages the runner received that its bag does not hold
    missing_from_bag: dict[str, int] = field(default_factory=dict)
    # samples a killed node was sending when it died, per topic (mill_bringup.lost_samples)
    lost_with_restarts: dict[str, int] = field(default_factory=dict)
    # what the drives said of foreign publishers on their topics (ignored)
    foreign_publishers: list[str] = field(default_factory=list)
    # what the runner says once of the statuses it heard (a drive status named otherwise)
    warnings: list[str] = field(default_factory=list)
    # axes the start handshake released (--rearm), with the stop each was latched by
    rearmed: dict[str, str] = field(default_factory=dict)
    error: str | None = None  # what stopped the run before the job completed
    differences: dict[str, float] | None = None  # against the offline run
    bag: dict[str, Any] | None = None
    record: Any = field(default=None, repr=False)

    @property
    def text(self) -> str:
        """The job's summary as text (printed from the summary)."""
        return self.summary.text()

    @property
    def failures(self) -> list[Event]:
        """What made the job fail (exit code 1): the summary's failures (a realtime axis
        that tripped, was stopped or braked; what stopped the run)."""
        return list(self.summary.failures)

    @property
    def intact(self) -> bool:
        """No sample missing from the record or the bag, nothing foreign in the record or in
        the drive's graph."""
        complete = not self.missing_samples and not self.missing_from_bag
        return complete and not self.foreign and not self.foreign_publishers

    @property
    def outcome(self) -> Outcome:
        """How the run ended: interrupted, refused, failed, or a good job whose record is
        complete or not."""
        kinds = {f.kind for f in self.failures}
        if INTERRUPTED in kinds:
            return Outcome.INTERRUPTED
        if REFUSED in kinds:
            return Outcome.REFUSED
        if kinds:
            return Outcome.FAILED
        return Outcome.GOOD if self.intact else Outcome.RECORD_INCOMPLETE

    @property
    def exit_code(self) -> int:
        """0 a good job, its record complete; 1 the job failed; 2 its start refused; 3 a
        good job whose record is incomplete; 130 interrupted (run_scenario's exit codes)."""
        return self.outcome.exit_code

    @property
    def offline_max_difference(self) -> float | None:
        return None if self.differences is None else max(self.differences.values(), default=0.0)

    def to_json(self) -> dict[str, Any]:
        d = {k: v for k, v in vars(self).items() if k not in ('record', 'summary')}
        d.update(self.summary.to_json())  # its failures among them
        d['outcome'] = self.outcome.value
        d['exit_code'] = self.exit_code
        d['offline_max_difference'] = self.offline_max_difference
        d['total_peak_rss_mb'] = sum(self.peak_rss_mb.values())
        return d


def ended(scenario: str, outcome: Outcome, error: str) -> dict[str, Any]:
    """The summary of a run that ended before it had a result (interrupted or stopped
    while its graph was planned or started): how, and why."""
    return {
        'scenario': scenario,
        'outcome': outcome.value,
        'exit_code': outcome.exit_code,
        'error': error,
        'events': [],
        'failures': [],
        'metrics': [],
    }


def write_summary(run_dir: Path, summary: RunResult | dict[str, Any]) -> None:
    """summary.json of one run (a variant's directory), however it ended."""
    data = summary.to_json() if isinstance(summary, RunResult) else summary
    (run_dir / 'summary.json').write_text(json.dumps(data, indent=2))


def format_result(r: RunResult) -> str:
    word = 'REFUSED' if r.outcome is Outcome.REFUSED else 'FAILED'
    lines = [f'{word}: {f.text()}' for f in r.failures]
    lines += [
        f'scenario {r.scenario}: {r.samples} samples, {r.sim_time:.3f} s of machine time',
        r.text,
        f'wall time {r.wall_time:.1f} s, real-time factor {r.real_time_factor:.2f}, '
        f'{r.steps_per_second:.0f} steps/s, {r.cpu_ms_per_step:.2f} ms CPU per step',
        f'peak RSS of the graph {sum(r.peak_rss_mb.values()):.0f} MB '
        f'({len(r.peak_rss_mb)} processes), {r.peak_pss_mb:.0f} MB in use together (PSS)',
    ]
    lines += bag_meta.loss_lines(r.missing_samples, r.missing_ranges)
    lines += [
        f'ERROR: {t}: the bag holds {n} messages fewer than the runner received'
        for t, n in r.missing_from_bag.items()
    ]
    if r.lost_with_restarts:
        lines.append(
            'note: samples lost with their killed sender (started again), not in the record: '
            f'{r.lost_with_restarts}'
        )
    lines += drop_lines(r.dropped)
    # who the drives saw publish on their topics besides the owners (the exit code 3 says
    # 'see above'): each foreign publisher and each contested owner's name, its claimants
    lines += [f'ERROR: {f}' for f in r.foreign_publishers]
    if r.foreign and not r.dropped:  # a job that counts them without the reasons
        lines.append(f'ERROR: messages from other senders or malformed, left out: {r.foreign}')
    lines += [f'WARNING: {w}' for w in r.warnings]
    if r.rearmed:
        lines.append(
            "re-armed before the start (--rearm, the drive's ~/release): "
            + '; '.join(f'{a} (stopped: {why})' for a, why in sorted(r.rearmed.items()))
        )
    if r.problems:
        lines.append('diagnostics: ' + '; '.join(r.problems[:5]))
    if r.differences is not None:
        lines.append(
            'max |distributed - offline|: '
            + ', '.join(f'{k} {v:.3e}' for k, v in r.differences.items())
        )
    if r.bag is not None:
        per_s = r.bag['bytes_per_sim_second']
        lines.append(
            f'bag {r.bag["path"]}: {r.bag["messages"]} messages, '
            f'{r.bag["size_bytes"] / 1e6:.1f} MB'
            + (f' ({per_s / 1e6:.2f} MB per simulated second)' if per_s else '')
        )
        dropped = describe_drops(r.bag.get('dropped') or {})
        if dropped:
            lines[-1] += f'; {dropped} (bad messages, not recorded)'
    return '\n'.join(lines)
