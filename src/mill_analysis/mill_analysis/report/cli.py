"""`report BAG [BAG ...]`: options, reading the bags, writing DIR/report.md and the plots.

A force job's bags (Rubio 2013: force samples, force stream, overrides) get the force report
(mill_analysis.report.force): J_c of eq. (14) computed from the recorded stream.

Bad input (a path that does not exist, an empty bag, a bag without the mill
topics, a file that is not MCAP, broken metadata) ends with one line
`report: error: ...` and exit code 1; bad options with one line and exit code 2.

While a bag is read and decoded, progress goes to stderr as the runner shows it
(mill_common.progress.Progress): a live bar on a terminal, a plain line every 5 s otherwise,
from 2 s into each phase.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path
from typing import NoReturn

from mill_bag.errors import BagError
from mill_bag.reader import open_bag
from mill_common.progress import Progress

from mill_analysis.force_record import is_force_bag, read_force_run
from mill_analysis.report.analysis import analyse
from mill_analysis.report.force import force_figure, force_markdown, force_table
from mill_analysis.report.plots import plot_all
from mill_analysis.report.text import markdown, text_table
from mill_analysis.run_record import read_run


class _BagProgress:
    """read_run's progress callback: one Progress per phase (reading, decoding) of a bag."""

    def __init__(self, label: str, quiet: bool) -> None:
        self.label = label
        self.quiet = quiet
        self.phase = ''
        self.bar: Progress | None = None

    def __call__(self, phase: str, done: int, total: int | None) -> None:
        if phase != self.phase:
            self.close()
            self.phase = phase
            self.bar = Progress(
                total,
                unit='messages',
                quiet=self.quiet,
                label=f'{self.label}: {phase}',
                decimals=0,
                delay=2.0,  # a short bag shows none (nor before a one-line error)
            )
        if self.bar is not None:
            self.bar.update(done)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:  # one line, no usage block
        print(f'{self.prog}: error: {message}', file=sys.stderr)
        raise SystemExit(2)


def _freqs(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(',') if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f'--freqs {text!r}: not a list of numbers') from None
    if not values or any(not (math.isfinite(v) and v > 0) for v in values):
        raise argparse.ArgumentTypeError(f'--freqs {text!r}: frequencies must be > 0')
    return values


def _positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text!r} is not a number') from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f'{text!r} must be > 0')
    return value


def _non_negative(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text!r} is not a number') from None
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f'{text!r} must be >= 0')
    return value


def labels_for(paths: list[Path]) -> list[str]:
    """Short distinct names: the bag directory, or its run directory for RUN/bag."""
    labels = []
    for p in paths:
        p = p.resolve()
        name = p.stem if p.is_file() else p.name
        if name == 'bag' or p.is_file():
            name = p.parent.name if name == 'bag' else name
        labels.append(name)
    if len(set(labels)) < len(labels):
        labels = [f'{i + 1}:{label}' for i, label in enumerate(labels)]
    return labels


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = _Parser(
        prog='report',
        description='Analyse rosbag2 bags of mill runs: print a table, write DIR/report.md '
        'and PNG plots. Several bags are compared side by side.',
    )
    parser.add_argument('bags', nargs='+', type=Path, metavar='BAG', help='bag directory or .mcap')
    parser.add_argument('--out', type=Path, help='output directory (default: BAG/../report)')
    parser.add_argument(
        '--skip', type=_non_negative, default=1.0, help='metrics over t >= SKIP [s] (default 1)'
    )
    parser.add_argument(
        '--freqs',
        type=_freqs,
        default=[60.0, 120.0],
        help='frequencies for the error amplitudes [Hz], comma separated (default 60,120)',
    )
    parser.add_argument(
        '--window',
        type=_positive,
        default=0.1,
        help='window of the largest windowed RMS tracking error [s] (default 0.1)',
    )
    parser.add_argument('--label', action='append', help='name of each bag in the report')
    parser.add_argument('--no-plots', action='store_true', help='table and report.md only')
    parser.add_argument('--quiet', '-q', action='store_true', help='no progress display')
    parser.add_argument(
        '--namespace',
        metavar='NAME',
        help='the machine namespace of the run, for a bag that holds several (default: the '
        "bag's only one)",
    )
    args = parser.parse_args(argv)
    if args.label and len(args.label) != len(args.bags):
        parser.error(f'{len(args.label)} --label for {len(args.bags)} bags')
    labels = args.label or labels_for(args.bags)
    kinds = []
    for bag in args.bags:
        try:
            kinds.append(is_force_bag(bag_topics(bag)))
        except (BagError, OSError):
            kinds.append(False)  # read_run below says what is wrong with it
    if any(kinds):
        if not all(kinds):
            print(
                'report: error: force-job bags and axis-job bags cannot share one report',
                file=sys.stderr,
            )
            return 1
        return force_report(args, labels, argv)
    reports = []
    t_start = time.monotonic()
    for bag, label in zip(args.bags, labels, strict=True):
        t0 = time.monotonic()
        progress = _BagProgress(label, args.quiet)
        try:
            run = read_run(bag, args.namespace, progress)
        except Exception as exc:
            print(f'report: error: {unreadable(bag, exc)}', file=sys.stderr)
            return 1
        finally:
            progress.close()
        if run.n <= 1 or not (run.record.t >= args.skip).any():
            print(
                f'report: error: {bag}: no samples at t >= {args.skip:g} s '
                f'(the run lasts {run.record.t[-1]:g} s)',
                file=sys.stderr,
            )
            return 1
        report = analyse(run, label, args.skip, args.window, args.freqs)
        report.read_seconds = time.monotonic() - t0
        reports.append(report)
    out = args.out or (args.bags[0].resolve().parent / 'report')
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        print(f'report: error: cannot create {out}: {exc.strerror}', file=sys.stderr)
        return 1
    big = sum(r.run.n for r in reports) > 20_000
    workers = min(2, os.cpu_count() or 1) if big else 1
    figures = [] if args.no_plots else plot_all(reports, out, workers)
    (out / 'report.md').write_text(markdown(reports, figures, argv) + '\n')
    print(text_table(reports))
    print(
        f'report {out / "report.md"} with {len(figures)} plots ({time.monotonic() - t_start:.1f} s)'
    )
    return 0


def bag_topics(path: Path) -> dict[str, int]:
    """The topics of a bag (from its metadata.yaml, else by reading it)."""
    bag = open_bag(path)
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


def unreadable(bag: Path, exc: Exception) -> str:
    """The one line report prints for a bag it cannot read."""
    if isinstance(exc, BagError):
        return str(exc)
    if isinstance(exc, OSError):
        return f'{bag}: {exc.strerror or exc}'
    # A damaged message in an otherwise readable bag.
    return f'{bag}: cannot read ({type(exc).__name__}: {exc})'


def force_report(args: argparse.Namespace, labels: list[str], argv: list[str]) -> int:
    """A force job's bags (Rubio 2013): J_c of eq. (14) and the override, side by side."""
    t_start = time.monotonic()
    runs = []
    for bag, label in zip(args.bags, labels, strict=True):
        try:
            runs.append((label, read_force_run(bag, args.namespace)))
        except Exception as exc:
            print(f'report: error: {unreadable(bag, exc)}', file=sys.stderr)
            return 1
    out = args.out or (args.bags[0].resolve().parent / 'report')
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        print(f'report: error: cannot create {out}: {exc.strerror}', file=sys.stderr)
        return 1
    figures = [] if args.no_plots else force_figure(runs, out)
    (out / 'report.md').write_text(force_markdown(runs, figures, argv) + '\n')
    print(force_table(runs))
    print(
        f'report {out / "report.md"} with {len(figures)} plots ({time.monotonic() - t_start:.1f} s)'
    )
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
