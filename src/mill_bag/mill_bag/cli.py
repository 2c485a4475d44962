"""Command line of mill_bag: `python -m mill_bag recover BAG`.

recover: rewrite the MCAP file of a killed recording (no footer) or a damaged one (flipped
bytes) as a complete bag that every reader opens (see mill_bag.recover). Each damaged part is
one line on stderr (`mill_bag: damaged: FILE: bytes A-B (a chunk): why; N messages lost, log
times ...`). Exit code 0: the bag is complete (now); 3: it is, but damaged parts were lost;
1: it cannot be recovered (one line); 2: bad arguments.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

from mill_common.one_line_parser import OneLineParser

from mill_bag.errors import BagError
from mill_bag.mcap_read import Damage
from mill_bag.recover import describe_loss, recover

PROG = 'mill_bag'


def main(argv: Sequence[str] | None = None) -> int:
    parser = OneLineParser(
        prog='python -m mill_bag',
        name=PROG,
        description='Rosbag2 MCAP bag tools. recover: rewrite the MCAP file of a killed '
        'recording (no footer) or a damaged one as a complete bag that every reader opens; '
        'one line per damaged part says what is lost (exit code 3).',
    )
    parser.add_argument('command', choices=['recover'])
    parser.add_argument('bag', help='bag directory or .mcap file')
    args = parser.parse_args(argv)
    damaged: list[Damage] = []
    try:
        kept, files = recover(args.bag, damaged)
    except BagError as exc:
        print(f'{PROG}: error: {exc}', file=sys.stderr)
        return 1
    except OSError as exc:
        print(f'{PROG}: error: {args.bag}: {exc.strerror or exc}', file=sys.stderr)
        return 1
    for damage in damaged:
        print(f'{PROG}: damaged: {damage}', file=sys.stderr)
    if files:
        lost = f'; {describe_loss(damaged)}' if damaged else ''
        print(f'{args.bag}: recovered {kept} messages in {files} file(s){lost}')
    else:
        print(f'{args.bag}: complete already ({kept} messages)')
    return 3 if any(d.messages != 0 for d in damaged) else 0
