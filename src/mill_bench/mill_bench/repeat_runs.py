"""Benchmark: one run_scenario command run again and again, beside busy loops if asked,
and beside a client that joins and leaves the run's domain if asked (--join-every).

    python -m mill_bench.repeat_runs                       # 10 realtime 1 kHz commissioning
                                                           # runs beside two busy loops
    python -m mill_bench.repeat_runs --runs 50 --busy 0 -- slotting   # the main job, quiet
    python -m mill_bench.repeat_runs --runs 3 --busy 0 --join-every 0.5 -- slotting \
        --duration 15                      # a participant joins the domain every 0.5 s

What a run's ending says is read from its summary.json (mill_bringup's runner writes one
for every ending): its exit code, the samples its record lacks, the drive's own stalls, and
the WARNING lines of its output. Printed: a line per run as it ends, then how many runs
ended with each exit code, how many lost a sample, and how many printed a warning. The
busy loops are `python3 -c 'while True: pass'` processes, killed at the end whatever
happens. Every run gets a private ROS domain on loopback.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import subprocess
import sys
import tempfile
from collections import Counter
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from mill_common.env import ros_environment

DEFAULT_RUN = (
    'commissioning',
    '--timing',
    'realtime',
    '--layout',
    'single',
    '--realtime-priority',
    '80',
    '--duration',
    '10',
)
TIMEOUT = 900.0  # a run that has not ended after this is killed and counted as such [s]


@dataclass(frozen=True)
class RunOutcome:
    exit_code: int
    missing: int  # samples the runner's record lacks, over every topic
    stalls: int  # the drive's own stalls it reported
    longest_stall_ms: float
    warnings: list[str]  # the run's WARNING lines
    load: float  # the one-minute load average at its end
    # a lockstep run's steps that waited over each threshold [ms] (mill_common.step_waits)
    waits_over: dict[int, int] = field(default_factory=dict)
    longest_wait_ms: float = 0.0

    def line(self, i: int) -> str:
        stall = f', longest {self.longest_stall_ms:.0f} ms' if self.stalls else ''
        waits = ''
        if self.waits_over:
            over = ' / '.join(f'{n}' for n in self.waits_over.values())
            waits = f', steps waiting over {"/".join(map(str, self.waits_over))} ms: {over}'
        return (
            f'run {i}: exit {self.exit_code}, {self.missing} samples missing, '
            f'{self.stalls} drive stalls{stall}, {len(self.warnings)} warnings, '
            f'load {self.load:.1f}{waits}'
        )


@contextlib.contextmanager
def busy_loops(n: int) -> Iterator[None]:
    procs = [subprocess.Popen([sys.executable, '-c', 'while True: pass']) for _ in range(max(0, n))]
    try:
        yield
    finally:
        for p in procs:
            p.kill()
            p.wait()


def outcome(run_dir: Path, code: int, output: str) -> RunOutcome:
    """What one run's summary.json and output say (a run with none: its exit code alone)."""
    try:
        summary = json.loads((run_dir / 'summary.json').read_text())
    except (OSError, ValueError):
        summary = {}
    stalls = summary.get('drive_stalls') or {}  # mill_analysis.summary: a realtime run's
    waits = summary.get('step_waits') or {}  # a lockstep run's
    with open('/proc/loadavg') as f:
        load = float(f.read().split()[0])
    return RunOutcome(
        exit_code=code,
        missing=sum(int(n) for n in (summary.get('missing_samples') or {}).values()),
        stalls=int(stalls.get('count', 0)),
        longest_stall_ms=float(stalls.get('longest_ms', 0.0)),
        warnings=[ln for ln in output.splitlines() if ln.startswith('WARNING')],
        load=load,
        waits_over={int(t): int(n) for t, n in (waits.get('over_ms') or {}).items()},
        longest_wait_ms=float(waits.get('longest_ms', 0.0)),
    )


@contextlib.contextmanager
def joiner(period: float, env: dict[str, str]) -> Iterator[None]:
    """mill_bench.joiner in the run's domain (period 0: none), terminated at the end."""
    if period <= 0:
        yield
        return
    cmd = [sys.executable, '-m', 'mill_bench.joiner', str(period)]
    proc = subprocess.Popen(cmd, env=env, stderr=subprocess.DEVNULL)
    try:
        yield
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def run_once(args: Sequence[str], run_dir: Path, join_every: float = 0.0) -> RunOutcome:
    base = dict(os.environ)
    base.pop('ROS_DOMAIN_ID', None)
    env = ros_environment(base)  # a private domain of its own
    cmd = [sys.executable, '-m', 'mill_bringup.runner', *args, '--output', str(run_dir)]
    cmd.append('--quiet')
    try:
        with joiner(join_every, env):
            proc = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired as exc:
        out = exc.stderr if isinstance(exc.stderr, str) else ''
        return outcome(run_dir, -1, out)
    return outcome(run_dir, proc.returncode, proc.stdout + proc.stderr)


def table(outcomes: Sequence[RunOutcome]) -> str:
    n = len(outcomes)
    codes = Counter(o.exit_code for o in outcomes)
    lines = [f'{n} runs: ' + ', '.join(f'exit {c}: {k}' for c, k in sorted(codes.items()))]
    lines.append(f'runs that lost a sample of their record: {sum(o.missing > 0 for o in outcomes)}')
    lines.append(f'runs with a WARNING line: {sum(bool(o.warnings) for o in outcomes)}')
    waited = [o for o in outcomes if o.waits_over]
    if waited:
        totals = Counter[int]()
        for o in waited:
            totals.update(o.waits_over)
        lines.append(
            'lockstep steps that waited over '
            + ', '.join(f'{t} ms: {n}' for t, n in sorted(totals.items()))
            + f' (in {sum(any(n for t, n in o.waits_over.items() if t >= 100) for o in waited)}'
            f' of {len(waited)} runs over 100 ms; the longest '
            f'{max(o.longest_wait_ms for o in waited):.1f} ms)'
        )
    stalled = [o.longest_stall_ms for o in outcomes if o.stalls]
    if stalled:
        lines.append(
            f'runs whose drive reported a stall: {len(stalled)}, the longest {max(stalled):.0f} ms'
        )
    return '\n'.join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog='python -m mill_bench.repeat_runs',
        description='Run one run_scenario command again and again (beside busy loops) and '
        'count how its runs end.',
    )
    parser.add_argument('--runs', type=int, default=10, help='how many runs (default 10)')
    parser.add_argument(
        '--busy', type=int, default=2, help='busy loops beside the runs (default 2)'
    )
    parser.add_argument(
        '--join-every',
        type=float,
        default=0.0,
        metavar='SECONDS',
        help='beside each run, a client that joins its domain (a participant reading the '
        'reference) and leaves after SECONDS, again and again (mill_bench.joiner; default 0: '
        'none)',
    )
    parser.add_argument(
        'run',
        nargs='*',
        help='run_scenario arguments (after --); default: ' + ' '.join(DEFAULT_RUN),
    )
    args = parser.parse_args(argv)
    if args.runs < 1:
        parser.error('--runs: at least 1')
    if args.join_every < 0:
        parser.error('--join-every: 0 (none) or more seconds')
    run = args.run or list(DEFAULT_RUN)
    joins = f', a client joining every {args.join_every:g} s' if args.join_every else ''
    print(
        f'{args.runs} runs of: run_scenario {" ".join(run)}; {args.busy} busy loops{joins}',
        flush=True,
    )
    outcomes = []
    with tempfile.TemporaryDirectory(prefix='repeat_runs_') as tmp, busy_loops(args.busy):
        for i in range(1, args.runs + 1):
            o = run_once(run, Path(tmp) / f'run{i}', args.join_every)
            outcomes.append(o)
            print(o.line(i), flush=True)
            for w in o.warnings[:3]:
                print(f'    {w[:200]}', flush=True)
    print(table(outcomes))
    return 0


if __name__ == '__main__':
    sys.exit(main())
