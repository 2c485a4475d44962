"""Check tool: the offline records of every scenario and variant, fingerprinted bit for bit.

    python -m mill_bench.offline_bits --duration 3 --write before.json    # on the old code
    python -m mill_bench.offline_bits --duration 3 --compare before.json  # on the new code

Runs each scenario of the config directories and each of its variants offline
(mill_bringup.jobs.base.simulate, the nodes' step objects) for `--duration` seconds of
machine time and takes a SHA-256 of its whole record: every array's dtype, shape and bytes
(NaN payloads included), every other field's repr, in field order. `--compare` prints the
runs whose fingerprint changed and exits 1 if any did. A change of speed that keeps the
arithmetic (same expressions in the same order) must leave every fingerprint as it was.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
import sys
from typing import Any

import numpy as np
from mill_bringup.catalogue import TRAJECTORY
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.registry import job_for

from mill_bringup import scenario as scenario_mod


def _feed(h: Any, value: Any) -> None:
    if isinstance(value, np.ndarray):
        h.update(f'{value.dtype}{value.shape}'.encode())
        h.update(np.ascontiguousarray(value).tobytes())
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        h.update(type(value).__name__.encode())
        for f in dataclasses.fields(value):
            h.update(f.name.encode())
            _feed(h, getattr(value, f.name))
    elif isinstance(value, dict):
        for key in sorted(value, key=repr):
            h.update(repr(key).encode())
            _feed(h, value[key])
    elif isinstance(value, list | tuple):
        h.update(f'[{len(value)}'.encode())
        for item in value:
            _feed(h, item)
    else:
        h.update(repr(value).encode())


def fingerprint(record: Any) -> str:
    """SHA-256 of a record's every bit (module docstring)."""
    h = hashlib.sha256()
    _feed(h, record)
    return h.hexdigest()


def runs() -> list[tuple[str, str | None]]:
    """(scenario, variant or None) of every scenario file and variant, sorted."""
    names = sorted(
        {p.stem for d in scenario_mod.config_dirs() if d.is_dir() for p in d.glob('*.yaml')}
    )
    out: list[tuple[str, str | None]] = []
    for name in names:
        try:
            scen = scenario_mod.load(name)
        except scenario_mod.ScenarioError:
            continue
        out.append((name, None))
        out.extend((name, v) for v in scen.variants)
    return out


def run_one(name: str, variant: str | None, duration: float) -> str:
    """The fingerprint of one offline run, or 'error: ...' (compared as it is)."""
    try:
        scen = scenario_mod.load(name)
        if variant is not None:
            scen = scen.variant(variant)
        for node in scen.nodes_of(TRAJECTORY):
            scen.add_override(f'{node.name}.duration={duration!r}')
        return fingerprint(simulate(job_for(scen)))
    except Exception as exc:  # a run that cannot run must fail the same way before and after
        return f'error: {type(exc).__name__}: {exc}'


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog='python -m mill_bench.offline_bits',
        description='Fingerprint the offline record of every scenario and variant.',
    )
    parser.add_argument('--duration', type=float, default=3.0, help='machine time per run [s]')
    parser.add_argument(
        '--only', metavar='PREFIX', action='append', help='runs whose name starts so (repeatable)'
    )
    group = parser.add_mutually_exclusive_group(required=True)
    group.add_argument('--write', metavar='FILE', help='write the fingerprints (JSON)')
    group.add_argument('--compare', metavar='FILE', help='compare with fingerprints written before')
    args = parser.parse_args(argv)
    prints: dict[str, str] = {}
    for name, variant in runs():
        key = name if variant is None else f'{name}/{variant}'
        if args.only and not any(key.startswith(p) for p in args.only):
            continue
        prints[key] = run_one(name, variant, args.duration)
        print(f'{key}: {prints[key][:16]}', file=sys.stderr)
    if args.write:
        with open(args.write, 'w', encoding='utf-8') as f:
            json.dump({'duration': args.duration, 'runs': prints}, f, indent=1)
        print(f'{len(prints)} runs fingerprinted ({args.duration} s each): {args.write}')
        return 0
    with open(args.compare, encoding='utf-8') as f:
        before = json.load(f)['runs']
    if args.only:
        before = {k: v for k, v in before.items() if k in prints}
    changed = sorted(k for k in set(before) | set(prints) if before.get(k) != prints.get(k))
    for key in changed:
        print(f'changed: {key}: {before.get(key, "-")[:16]} -> {prints.get(key, "-")[:16]}')
    same = len(prints) - len([k for k in changed if k in prints])
    print(f'{same} of {len(prints)} runs the same to the bit ({args.duration} s each)')
    return 1 if changed else 0


if __name__ == '__main__':
    raise SystemExit(main())
