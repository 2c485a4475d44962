"""What a run gives: RunResult (figures of the run and of its job) and its text."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from mill_analysis.record_checks import drop_lines
from mill_bag.intake import describe as describe_drops

from mill_analysis import records


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
    summary: dict[str, Any]  # the job's own figures (jobs.base.Job.summary_json)
    text: str  # the job's summary as text
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
    # what made the job fail (a realtime axis that tripped or was braked): exit code 1
    failures: list[str] = field(default_factory=list)
    differences: dict[str, float] | None = None  # against the offline run
    bag: dict[str, Any] | None = None
    record: Any = field(default=None, repr=False)

    @property
    def intact(self) -> bool:
        """No sample missing from the record or the bag, nothing foreign in the record or in
        the drive's graph."""
        owned = not any('ownership' in p for p in self.problems)
        complete = not self.missing_samples and not self.missing_from_bag
        return complete and not self.foreign and owned

    @property
    def offline_max_difference(self) -> float | None:
        return None if self.differences is None else max(self.differences.values(), default=0.0)

    def to_json(self) -> dict[str, Any]:
        d = {k: v for k, v in vars(self).items() if k not in ('record', 'summary', 'text')}
        d.update(self.summary)
        d['offline_max_difference'] = self.offline_max_difference
        d['total_peak_rss_mb'] = sum(self.peak_rss_mb.values())
        return d


def format_result(r: RunResult) -> str:
    lines = [f'FAILED: {f}' for f in r.failures]
    lines += [
        f'scenario {r.scenario}: {r.samples} samples, {r.sim_time:.3f} s of machine time',
        r.text,
        f'wall time {r.wall_time:.1f} s, real-time factor {r.real_time_factor:.2f}, '
        f'{r.steps_per_second:.0f} steps/s, {r.cpu_ms_per_step:.2f} ms CPU per step',
        f'peak RSS of the graph {sum(r.peak_rss_mb.values()):.0f} MB '
        f'({len(r.peak_rss_mb)} processes), {r.peak_pss_mb:.0f} MB in use together (PSS)',
    ]
    lines += records.loss_lines(r.missing_samples, r.missing_ranges)
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
    if r.foreign and not r.dropped:  # a job that counts them without the reasons
        lines.append(f'ERROR: messages from other senders or malformed, left out: {r.foreign}')
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
