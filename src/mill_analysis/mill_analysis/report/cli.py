"""`report BAG [BAG ...]`: options, reading the bags, writing DIR/report.md and the plots.

Each bag is read, summarised and plotted through its kind of record (mill_analysis.report.kinds):
the one the bag names (run_scenario --record writes its job kind's), else the one its topics
tell. An axis job's bags get tracking and estimation errors, spectra and loop timing; a force
job's (Rubio 2013: force samples, force stream, overrides) J_c of eq. (14) computed from the
recorded stream (mill_analysis.report.force). Both kinds cannot share one report.

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
import sys
import time
from pathlib import Path

from mill_bag.errors import BagError
from mill_common.one_line_parser import OneLineParser, non_negative, positive

from mill_analysis.report.kinds import ReportOptions, kind_of


def _freqs(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(',') if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f'--freqs {text!r}: not a list of numbers') from None
    if not values or any(not (math.isfinite(v) and v > 0) for v in values):
        raise argparse.ArgumentTypeError(f'--freqs {text!r}: frequencies must be > 0')
    return values


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
    parser = OneLineParser(
        prog='report',
        description='Analyse rosbag2 bags of mill runs: print a table, write DIR/report.md '
        'and PNG plots. Several bags are compared side by side.',
    )
    parser.add_argument('bags', nargs='+', type=Path, metavar='BAG', help='bag directory or .mcap')
    parser.add_argument('--out', type=Path, help='output directory (default: BAG/../report)')
    parser.add_argument(
        '--skip', type=non_negative, default=1.0, help='metrics over t >= SKIP [s] (default 1)'
    )
    parser.add_argument(
        '--freqs',
        type=_freqs,
        default=[60.0, 120.0],
        help='frequencies for the error amplitudes [Hz], comma separated (default 60,120)',
    )
    parser.add_argument(
        '--window',
        type=positive,
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
    options = ReportOptions(args.skip, args.window, args.freqs, args.namespace, args.quiet)
    return write_report(args.bags, labels, options, args.out, args.no_plots, argv)


def write_report(
    bags: list[Path],
    labels: list[str],
    options: ReportOptions,
    out: Path | None,
    no_plots: bool,
    argv: list[str],
) -> int:
    """Read each bag through its kind of record, then write the report of them all."""
    kinds = []
    for bag in bags:
        try:
            kinds.append(kind_of(bag))
        except Exception as exc:
            print(f'report: error: {unreadable(bag, exc)}', file=sys.stderr)
            return 1
    shared = sorted({kind.REPORT for kind in kinds}, reverse=True)
    if len(shared) > 1:
        mixed = ' bags and '.join(shared)
        print(f'report: error: {mixed} bags cannot share one report', file=sys.stderr)
        return 1
    t_start = time.monotonic()
    runs = []
    for bag, label, kind in zip(bags, labels, kinds, strict=True):
        try:
            runs.append(kind.read(bag, label, options))
        except Exception as exc:
            print(f'report: error: {unreadable(bag, exc)}', file=sys.stderr)
            return 1
    out = out or (bags[0].resolve().parent / 'report')
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        print(f'report: error: cannot create {out}: {exc.strerror}', file=sys.stderr)
        return 1
    shown = kinds[0]  # every kind of one REPORT shows the others' runs
    figures = [] if no_plots else shown.plot(runs, out)
    (out / 'report.md').write_text(shown.markdown(runs, figures, argv) + '\n')
    print(shown.table(runs))
    print(
        f'report {out / "report.md"} with {len(figures)} plots ({time.monotonic() - t_start:.1f} s)'
    )
    return 0


def unreadable(bag: Path, exc: Exception) -> str:
    """The one line report prints for a bag it cannot read."""
    if isinstance(exc, BagError):
        return str(exc)
    if isinstance(exc, OSError):
        return f'{bag}: {exc.strerror or exc}'
    # A damaged message in an otherwise readable bag.
    return f'{bag}: cannot read ({type(exc).__name__}: {exc})'


if __name__ == '__main__':
    raise SystemExit(main())
