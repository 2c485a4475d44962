"""Command line of mill_bag: `python -m mill_bag recover BAG`.

recover: rewrite the MCAP file of a killed recording (no footer) as a complete bag
that every reader opens (see mill_bag.recover). Errors are one line on stderr:
exit code 1 for a bag that cannot be recovered, 2 for bad arguments.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import NoReturn

from mill_bag.errors import BagError
from mill_bag.recover import recover

PROG = 'mill_bag'


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:  # one line, no usage block
        print(f'{PROG}: error: {message}', file=sys.stderr)
        raise SystemExit(2)


def main(argv: Sequence[str] | None = None) -> int:
    parser = _Parser(
        prog='python -m mill_bag',
        description='Rosbag2 MCAP bag tools. recover: rewrite the MCAP file of a killed '
        'recording (no footer) as a complete bag that every reader opens.',
    )
    parser.add_argument('command', choices=['recover'])
    parser.add_argument('bag', help='bag directory or .mcap file')
    args = parser.parse_args(argv)
    try:
        kept, files = recover(args.bag)
    except BagError as exc:
        print(f'{PROG}: error: {exc}', file=sys.stderr)
        return 1
    except OSError as exc:
        print(f'{PROG}: error: {args.bag}: {exc.strerror or exc}', file=sys.stderr)
        return 1
    if files:
        print(f'{args.bag}: recovered {kept} messages in {files} file(s)')
    else:
        print(f'{args.bag}: complete already ({kept} messages)')
    return 0
