"""docs_figures: print every figure of the docs, check the docs against them, or rewrite.

docs_figures                      # every figure: id, value, the command behind it
docs_figures --check              # exit 1 and one line per figure the docs misquote
docs_figures --write              # rewrite the marked figures in the docs
docs_figures --group beltran      # only these groups (several allowed)
docs_figures --image              # regenerate docs/img/slotting_tracking_error.*
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from mill_bringup.docs_figures import markers
from mill_bringup.docs_figures.registry import GROUPS, MEASURED, compute, group_of

DOCS = ('README.md', 'docs/*.md')  # relative to --root


def documents(root: Path) -> list[Path]:
    return [p for pattern in DOCS for p in sorted(root.glob(pattern))]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog='docs_figures', description='Print, check or rewrite the figures of the docs.'
    )
    parser.add_argument('--root', type=Path, default=Path('.'), help='the repository (.)')
    parser.add_argument('--group', action='append', choices=sorted(GROUPS), help='only these')
    parser.add_argument('--no-system', action='store_true', help='leave out the ROS groups')
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument('--check', action='store_true', help='compare the docs with the figures')
    mode.add_argument('--write', action='store_true', help='rewrite the docs with the figures')
    args = parser.parse_args(argv)
    docs = documents(args.root)
    if not docs:
        print(f'docs_figures: error: no README.md or docs/*.md under {args.root}', file=sys.stderr)
        return 2
    names = args.group or [g for g in GROUPS if not (args.no_system and GROUPS[g].system)]
    figures: dict[str, str] = {}
    for name in names:
        figures.update(got := compute(name))
        if not (args.check or args.write):
            print(f'# {name}: {GROUPS[name].command}')
            for fid, value in got.items():
                print(f'{fid} = {value}')
    if not (args.check or args.write):
        return 0
    problems = []
    quoted: set[str] = set()
    for path in docs:
        text = path.read_text(encoding='utf-8')
        if args.write:
            new = markers.rewrite(text, figures)
            if new != text:
                path.write_text(new, encoding='utf-8')
                print(f'rewrote {path}')
            text = new
        quoted |= {f.id for f in markers.find(text)}
        problems += markers.differences(
            text,
            figures,
            str(path),
            lambda fid: group_of(fid) in names or group_of(fid) not in GROUPS,
        )
    problems += [
        f'{fid}: printed, but no document quotes it' for fid in figures if fid not in quoted
    ]
    for m in MEASURED:  # left out on purpose: registry.MEASURED
        print(f'not checked: {m.document}: {m.text!r} ({m.how})')
    for line in problems:
        print(line)
    return 1 if problems else 0


if __name__ == '__main__':
    raise SystemExit(main())
