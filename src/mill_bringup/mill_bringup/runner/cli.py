"""The run_scenario command: every variant of a scenario across processes, its results and the
paper's verdicts (python -m mill_bringup.runner; see mill_bringup.runner)."""

from __future__ import annotations

import argparse
import datetime as dt
import signal
import sys
from pathlib import Path
from typing import Any

from mill_bag.errors import BagError
from mill_common.executable import STOP_SIGNALS, interrupt_once, release_stop_signals
from mill_common.realtime_setup import LISTENER_BELOW, listener_priority

from mill_analysis import papers
from mill_bringup.cli import add_scenario_arguments, load_scenario, run_parameters
from mill_bringup.jobs.base import Job
from mill_bringup.jobs.registry import job_for
from mill_bringup.runner.options import RunError, RunOptions
from mill_bringup.runner.result import (
    GOOD,
    INTERRUPTED_CODE,
    JOB_FAILED,
    RECORD_INCOMPLETE,
    START_REFUSED,
    Outcome,
    ended,
    format_result,
    write_summary,
)
from mill_bringup.runner.run import run
from mill_bringup.scenario import Scenario, ScenarioError, check_layout
from mill_common import topics

# run_scenario's exit codes, from the least to the most severe: 0 good and complete, 3 a good
# job with an incomplete record, 2 a start refused (and usage, argparse), 1 the job failed,
# 130 interrupted
SEVERITY = (GOOD, RECORD_INCOMPLETE, START_REFUSED, JOB_FAILED, INTERRUPTED_CODE)
STAY_NEEDS_REALTIME = (
    '--stay keeps the graph up after its job for manual commands, which need timing realtime '
    "(a lockstep job replays on the plant's clock): add --timing realtime"
)


def _apply_namespace(
    scen: Scenario, runs: dict[str, Scenario], namespace: str | None, private_clock: bool
) -> None:
    """--namespace and --private-clock on the scenario and each of its variants."""
    for s in (scen, *runs.values()):
        if namespace is not None:
            s.set_namespace(namespace)
        s.private_clock = s.private_clock or private_clock
    if scen.private_clock and scen.namespace == topics.ROOT:
        raise ScenarioError('a private clock needs a namespace (--namespace NAME)')


def parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog='run_scenario',
        description='Start every node of a scenario (each in its own process, or as --layout '
        'says), run the job in '
        'lockstep and print its results.',
        epilog='exit codes: 0 the job went well and its record is complete; 1 the job failed '
        '(an axis tripped, stopped or braked on a machine, the drive went silent, a node died, '
        'the run could not go on) or could not start; 2 usage, or the job refused to start '
        '(an axis the drive holds stopped from an earlier job: --rearm); 3 the job went well '
        "but the runner's record of it is incomplete (samples missing, foreign messages); 130 "
        'interrupted. Each run writes summary.json (its outcome and exit_code), however it '
        'ends.',
    )
    add_scenario_arguments(parser)
    parser.add_argument('--output', type=Path, help='run directory (default runs/NAME-TIME)')
    parser.add_argument('--domain-id', help='ROS_DOMAIN_ID (default: yours, else private)')
    parser.add_argument(
        '--stall-timeout',
        type=float,
        default=30.0,
        help='give up when no sample arrives for this long [s]; for a process that '
        '--respawn just started again, at least as long as a start-up may take',
    )
    parser.add_argument(
        '--startup-timeout',
        type=float,
        default=RunOptions.startup_timeout,
        help='give up when the job has not made its first step this long after the start, '
        'e.g. a driver (--external) that does not answer [s] (default %(default)g: start-up '
        'can take a minute on a loaded machine)',
    )
    parser.add_argument(
        '--compare-offline',
        action='store_true',
        help='also run the offline simulator and print the largest differences',
    )
    parser.add_argument(
        '--record',
        nargs='?',
        const='',
        metavar='BAG',
        help='write every topic to a rosbag2 bag (MCAP) in directory BAG, which must not '
        'exist (default: RUN_DIR/bag)',
    )
    parser.add_argument(
        '--namespace',
        metavar='NAME',
        help="run every node under this machine namespace (default: the scenario's, else /); "
        '/clock and /diagnostics stay global',
    )
    parser.add_argument(
        '--private-clock',
        action='store_true',
        help='remap the simulation clock /clock to NAMESPACE/clock, so that several '
        'simulated machines can run in one domain at the same time',
    )
    parser.add_argument('--quiet', '-q', action='store_true', help='no progress display')
    parser.add_argument(
        '--external',
        action='append',
        default=[],
        metavar='NODE',
        help='a node of the scenario that runs elsewhere, e.g. a hardware driver (repeatable)',
    )
    parser.add_argument(
        '--respawn',
        action='store_true',
        help='start a node that dies again (not the plant); it rejoins the running job (the '
        'plant and the peers then wait for a node as long as a start-up may take)',
    )
    parser.add_argument(
        '--realtime-priority',
        type=int,
        metavar='N',
        help='SCHED_FIFO priority 1-98 of the drive and of the processes of the axis nodes '
        '(their realtime_priority parameter: memory locked, garbage collector frozen), and of '
        f'the runner {LISTENER_BELOW} below it (--runner-priority); where the system '
        'refuses, each says so in one line and goes on',
    )
    parser.add_argument(
        '--runner-priority',
        type=int,
        metavar='N',
        help="SCHED_FIFO priority of the runner's own threads (the monitor that takes every "
        "message of the run's record), 0 the normal scheduler; default: with "
        f'--realtime-priority P, P - {LISTENER_BELOW} (at least 1: below the graph, above '
        'other load, so that the record keeps up), else 0; the processes it starts do not '
        'inherit it',
    )
    parser.add_argument(
        '--rearm',
        action='store_true',
        help='an axis an --external drive holds stopped from an earlier job (its status says '
        "<axis>.stopped) is released through the drive's ~/release before any node of the job "
        'starts; without it the job refuses to start on such an axis (exit code 2)',
    )
    parser.add_argument(
        '--layout',
        metavar='LAYOUT',
        help='which nodes share a process: processes (each its own), per_axis (observer and '
        "controller of an axis together), single (all in one); default: the scenario's "
        '(mill_scenario: layout:), else processes',
    )
    parser.add_argument(
        '--view',
        action='store_true',
        help='also start machine_view beside the graph, in its namespace and domain, as the '
        "launch does: the machine's URDF on robot_description (transient local) and the "
        'measured tool trace on mill/tool_trace, for RViz or Foxglove; stopped with the graph, '
        'its output in RUN_DIR/logs/machine_view.log',
    )
    parser.add_argument(
        '--stay',
        action='store_true',
        help='timing realtime: once the job is done keep the graph up, the axes held at rest, '
        "for manual commands (the trajectory's ~/jog, ~/home, ~/set_home, ~/mdi), until "
        'Ctrl-C or SIGTERM, which then end the run as that of a complete job (what the '
        'machine says meanwhile counts in the summary too: a trip while jogging fails it)',
    )
    return parser


def bag_paths(
    record: str | None, runs: dict[str, Scenario], run_dir: Path
) -> dict[str, Path | None]:
    """Where --record writes each variant's bag (None: not recorded); none may exist yet."""
    bags: dict[str, Path | None] = {}
    for name in runs:
        bags[name] = None
        if record is not None:
            bag = Path(record) if record else (run_dir / name) / 'bag'
            path = bag / name if name and record else bag
            bags[name] = path
            if path.exists():
                raise RunError(f'--record: {path} exists already; a bag is never overwritten')
    return bags


def run_options(args: argparse.Namespace, bag: Path | None) -> RunOptions:
    return RunOptions(
        skip=args.skip,
        stall_timeout=args.stall_timeout,
        startup_timeout=args.startup_timeout,
        quiet=args.quiet,
        domain_id=args.domain_id,
        compare_offline=args.compare_offline,
        record_bag=bag,
        respawn=args.respawn,
        external=frozenset(args.external),
        layout=args.layout,
        rearm=args.rearm,
        runner_priority=runner_priority(args),
        view=args.view,
        stay=args.stay,
    )


def runner_priority(args: argparse.Namespace) -> int:
    """--runner-priority, else one below --realtime-priority (at least 1), else 0."""
    if args.runner_priority is not None:
        return max(0, args.runner_priority)
    if args.realtime_priority:
        return listener_priority(args.realtime_priority)
    return 0


def paper_text(
    paper: str,
    jobs: dict[str, Job[Any]],
    records: dict[str, Any],
    parameters: papers.Parameters | None = None,
) -> str:
    """The paper's metrics and verdicts of the variants' records, after what each kind of
    job says of them (a realtime run is no reproduction); parameters: run_parameters."""
    text = papers.report(paper, records, parameters)
    notes = dict.fromkeys(job.PAPER_NOTE for job in jobs.values() if job.PAPER_NOTE)
    if text and notes:
        text = ''.join(f'{note}\n' for note in notes) + text
    return text


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    # SIGTERM ends the run like Ctrl-C: the graph is stopped and the bag closed.
    for signum in STOP_SIGNALS:
        signal.signal(signum, interrupt_once)
    records: dict[str, Any] = {}
    code = GOOD
    # the run directory of the variant under way, until its summary is written: an ending
    # without a result (an error or an interrupt before the run had one) writes it there
    pending: tuple[Path, str] | None = None
    try:
        release_stop_signals()  # held since the first line (mill_common.executable)
        scen, runs = load_scenario(args)
        if args.realtime_priority is not None:
            for variant in {id(r): r for r in (scen, *runs.values())}.values():
                variant.add_override(f'*.realtime_priority={args.realtime_priority}')
        if args.layout is not None:
            check_layout(args.layout)
        _apply_namespace(scen, runs, args.namespace, args.private_clock)
        jobs = {name: job_for(variant) for name, variant in runs.items()}  # all checked first
        for job in jobs.values():  # nobody resumes a pause in a run_scenario run
            unattended = getattr(job, 'unattended_pause', lambda: None)()
            if unattended is not None:
                raise RunError(unattended)
        if args.stay and not all(j.config.timing == 'realtime' for j in jobs.values()):
            raise RunError(STAY_NEEDS_REALTIME)
        if args.compare_offline and not all(j.HAS_OFFLINE_TWIN for j in jobs.values()):
            raise RunError('--compare-offline: a realtime run has no offline twin')
        stamp = dt.datetime.now().strftime('%Y%m%d-%H%M%S')
        run_dir = args.output or Path('runs') / f'{scen.name}-{stamp}'
        bags = bag_paths(args.record, runs, run_dir)
        run_dir.mkdir(parents=True, exist_ok=True)
        print(f'{scen.description}\nrun directory {run_dir}', file=sys.stderr)
        for name, job in jobs.items():
            variant_dir = run_dir / name if name else run_dir
            variant_dir.mkdir(parents=True, exist_ok=True)
            pending = (variant_dir, scen.name)
            if name:
                print(f'variant {name}: {" ".join(scen.variants[name])}', file=sys.stderr)
            result = run(job, variant_dir, run_options(args, bags[name]))
            records[name] = result.record
            code = max(code, result.exit_code, key=SEVERITY.index)
            write_summary(variant_dir, result)  # every ending: a dead drive, a refusal, Ctrl-C
            pending = None
            if name:
                print(f'variant {name}:')
            print(format_result(result))
            if result.outcome is Outcome.INTERRUPTED:
                print('run_scenario: interrupted', file=sys.stderr)
                return INTERRUPTED_CODE
            if result.error is not None:  # the run stopped: the next variants do not run
                print(f'run_scenario: error: {result.error}', file=sys.stderr)
                return result.exit_code
    except (ScenarioError, RunError, BagError) as exc:
        print(f'run_scenario: error: {exc}', file=sys.stderr)
        if pending is None:  # refused before anything started: the input's fault
            return START_REFUSED
        write_summary(pending[0], ended(pending[1], Outcome.FAILED, str(exc)))
        return JOB_FAILED
    except KeyboardInterrupt:
        print('run_scenario: interrupted', file=sys.stderr)
        if pending is not None:
            said = 'interrupted (Ctrl-C or SIGTERM) before the run had a result'
            write_summary(pending[0], ended(pending[1], Outcome.INTERRUPTED, said))
        return INTERRUPTED_CODE
    configs = {name: job.config for name, job in jobs.items()}
    text = paper_text(scen.paper, jobs, records, run_parameters(configs))
    if text:
        print(text)
        (run_dir / 'paper.txt').write_text(text + '\n')
    if code == JOB_FAILED:
        print(
            'run_scenario: error: the job failed on the machine (see FAILED above)', file=sys.stderr
        )
    elif code == START_REFUSED:
        print('run_scenario: error: the job refused to start (see REFUSED above)', file=sys.stderr)
    elif code == RECORD_INCOMPLETE:
        print(
            "run_scenario: the job went well, but the runner's record of it is incomplete or "
            'foreign messages were seen (see above)',
            file=sys.stderr,
        )
    return code
