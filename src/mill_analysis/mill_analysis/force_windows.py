"""Mean force and feed override of a recorded force-controlled run, per time window.

    python -m mill_analysis.force_windows RUN/bag 1 3 6 8 11 14.4

Reads /mill/force_control/state (the force controller's force, reference, feed command,
override, active β and depth of every control period) from a bag.
"""

from __future__ import annotations

import argparse
import itertools
import math
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from mill_bag.cdr import joint_state_cdr
from mill_bag.reader import open_bag

from mill_common import topics


class WindowError(RuntimeError):
    """The bag has no force-control state; str() says why."""


def state_windows(
    bag_path: str | Path, edges: Sequence[float]
) -> list[tuple[float, float, int, float, float]]:
    """(start, end, samples, mean force [N], mean override) of /mill/force_control/state
    per time window [edges[i], edges[i+1]) of a recorded run."""
    # The run may be under a machine namespace; a bag of several machines is refused.
    per_name: dict[str, list[tuple[float, float, float]]] = {}
    for name, _type, _log, _pub, data in open_bag(bag_path).read():
        if not topics.namespaces_with([name], topics.FORCE_CONTROL_STATE):
            continue
        msg = joint_state_cdr(data)
        if msg is not None:
            t = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
            # force, override (STATE_NAMES)
            per_name.setdefault(name, []).append((t, msg.position[0], msg.position[3]))
    if len(per_name) > 1:
        raise WindowError(
            f'{bag_path}: force control states of several machines: {sorted(per_name)}'
        )
    rows = next(iter(per_name.values()), [])
    if not rows:
        raise WindowError(f'{bag_path}: no {topics.FORCE_CONTROL_STATE} messages')
    table = np.array(rows)
    out = []
    for a, b in itertools.pairwise(edges):
        sel = (table[:, 0] >= a) & (table[:, 0] < b)
        n = int(np.count_nonzero(sel))
        force = float(np.mean(table[sel, 1])) if n else math.nan
        override = float(np.mean(table[sel, 2])) if n else math.nan
        out.append((a, b, n, force, override))
    return out


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog='python -m mill_analysis.force_windows',
        description='Mean force and feed override of a recorded force-controlled run, per '
        'time window (from /mill/force_control/state).',
    )
    parser.add_argument('bag', help='bag directory or .mcap file (run_scenario --record)')
    parser.add_argument('edges', nargs='+', type=float, help='window edges [s], increasing')
    args = parser.parse_args(argv)
    if len(args.edges) < 2 or any(b <= a for a, b in itertools.pairwise(args.edges)):
        parser.error('give at least two increasing window edges')
    try:
        windows = state_windows(args.bag, args.edges)
    except (WindowError, OSError, ValueError) as exc:
        print(f'force_windows: error: {exc}', file=sys.stderr)
        return 1
    print('window [s]       samples   force [N]   override')
    for a, b, n, force, override in windows:
        print(f'{a:6.2f}-{b:6.2f}  {n:9d}  {force:10.1f}  {override:9.3f}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
