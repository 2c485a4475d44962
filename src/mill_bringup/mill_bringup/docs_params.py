"""docs_params: the parameter tables of docs/parameters.md, made from the declarations.

docs_params            # print the page
docs_params --check    # exit 1 if docs/parameters.md differs from what the declarations give
docs_params --write    # rewrite docs/parameters.md

Every node kind of the catalogue (and the recorder) lists its parameters as declared once
(mill_common.declared): name, type, default, unit, accepted values, read-only, description.
The page is never edited by hand; a test checks it, as docs_figures checks the figures.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from pathlib import Path

from mill_common.parameters import ParamSpec, value_type

from mill_bringup.catalogue import KINDS

PAGE = Path('docs/parameters.md')
HEADER = """# Parameters

Every parameter of every node, as its code declares it (one declaration per parameter:
`mill_common.declared`). This page is generated: `docs_params --write` rewrites it and a
test (`docs_params --check`) fails when it differs from the declarations. `NODE --help`
prints the same for one node, and `ros2 param describe` gives each one's range.

Read-only parameters are taken when the node starts (a file, `-p`); the others can also be
changed while it runs (`ros2 param set`): a refused value leaves the node as it was.
"""


def _value(value: object) -> str:
    if isinstance(value, float) and math.isinf(value):
        return '.inf' if value > 0 else '-.inf'
    if isinstance(value, str):
        return f"'{value}'"
    if isinstance(value, list | tuple):
        return '[' + ', '.join(_value(v) for v in value) + ']'
    if isinstance(value, bool):
        return 'true' if value else 'false'
    return repr(value)


def _cell(text: str) -> str:
    return text.replace('|', '\\|').replace('\n', ' ')


def _description(spec: ParamSpec) -> str:
    unit = f' [{spec.unit}]'
    if spec.unit and spec.description.endswith(unit):
        return spec.description[: -len(unit)]
    return spec.description


def table(specs: Sequence[tuple[str, ParamSpec]]) -> str:
    rows = [
        '| parameter | type | default | unit | accepted | run time | description |',
        '|---|---|---|---|---|---|---|',
    ]
    for name, spec in specs:
        accepted = getattr(spec.check, 'text', '') or ''
        rows.append(
            '| '
            + ' | '.join(
                _cell(c)
                for c in (
                    f'`{name}`',
                    value_type(spec),
                    f'`{_value(spec.default)}`',
                    spec.unit,
                    accepted,
                    'read-only' if spec.read_only else 'yes',
                    _description(spec),
                )
            )
            + ' |'
        )
    return '\n'.join(rows)


def _recorder_specs() -> list[tuple[str, ParamSpec]]:
    from mill_bag.recorder import parameter_specs

    return parameter_specs()


def page() -> str:
    parts = [HEADER]
    sections = [
        (f'{kind.package} {kind.executable}', kind.description, kind.parameter_specs())
        for kind in KINDS
    ]
    sections.append(('mill_bag recorder', 'the rosbag2 (MCAP) recorder', _recorder_specs()))
    for title, description, specs in sections:
        parts.append(f'## `{title}`\n\n{description[:1].upper()}{description[1:]}.\n')
        parts.append(table(specs) + '\n')
    return '\n'.join(parts)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog='docs_params', description='Print, check or rewrite docs/parameters.md.'
    )
    parser.add_argument('--root', type=Path, default=Path('.'), help='the repository (.)')
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument('--check', action='store_true', help='compare the page with the code')
    mode.add_argument('--write', action='store_true', help='rewrite the page')
    args = parser.parse_args(argv)
    text = page()
    path = args.root / PAGE
    if args.write:
        path.write_text(text, encoding='utf-8')
        print(f'wrote {path}')
        return 0
    if not args.check:
        print(text, end='')
        return 0
    if not path.exists():
        print(f'docs_params: {path} is missing: docs_params --write makes it', file=sys.stderr)
        return 1
    if path.read_text(encoding='utf-8') != text:
        print(f'docs_params: {path} differs from the declarations: docs_params --write')
        return 1
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
