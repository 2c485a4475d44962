"""`identify BAG`: the model of every axis from a recorded identify run, its table and plot.

Reads the positions and commands of a bag (`run_scenario identify --record`, or any bag of
the mill topics with enough motion), chooses each axis's model (mill_models.axis_model: the
rigid fit, its frequency response, backlash, low-speed friction), prints the tables, plots
model against measurement on held-out data and writes the machine model that `tune` reads.
Every axis says which model it got and why. An axis whose record shows a resonance gets the
two-mass model, written to the file with its slow rigid fit (gain, friction and load at the
delay its response shows), for which `tune` designs; any axis the record cannot give a
model gets one line saying why and no model file is written (exit 1); bad options and
unreadable bags one line (exit 2 / 1).
"""

from __future__ import annotations

import sys
from pathlib import Path

from mill_bag.errors import BagError
from mill_common.one_line_parser import OneLineParser, positive
from mill_models.axis_model import NONE, RIGID, TWO_MASS, StructureSettings
from mill_models.identification import FitSettings

from mill_analysis.bag_run import read_run
from mill_analysis.identify import machine_file
from mill_analysis.identify.fit_axes import structure_record
from mill_analysis.identify.plot import plot
from mill_analysis.identify.table import structure_table, table


def _parser() -> OneLineParser:
    p = OneLineParser(
        prog='identify',
        description='Identify each axis of a recorded run (run_scenario identify --record): '
        "input gain b, viscous and Coulomb friction, constant load and delay of x'' = "
        "b·u(t − d·T) − α·x' − β·sign(x') − γ, with 95 %% intervals, or the two-mass model "
        'when the frequency response shows a resonance; breakaway and Stribeck friction and '
        'backlash; which model each axis got and why; the tables, a plot of model against '
        'held-out measurement, and the machine model file that tune reads.',
    )
    p.add_argument('bag', help='bag directory or .mcap file')
    p.add_argument('--output', '-o', type=Path, help='machine model (default: BAG/../machine.yaml)')
    p.add_argument('--plot', type=Path, help='plot file (default: BAG/../identify.png)')
    p.add_argument('--axes', default='x,y,z', help='axes to identify (default x,y,z)')
    p.add_argument('--skip', type=float, default=1.0, help='leave out t < SKIP [s] (default 1)')
    p.add_argument(
        '--max-delay', type=int, default=5, help='largest delay tried [samples] (default 5)'
    )
    p.add_argument('--pitch', type=positive, help='screw pitch [m/rev]: also print forces in N')
    return p


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    axes = [a.strip() for a in args.axes.split(',') if a.strip()]
    if not axes or any(a not in 'xyz' or len(a) != 1 for a in axes):
        print(f'identify: error: --axes {args.axes!r}: a list of x, y, z', file=sys.stderr)
        return 2
    if args.max_delay < 1:
        print('identify: error: --max-delay must be at least 1', file=sys.stderr)
        return 2
    try:
        run = read_run(args.bag)
    except (BagError, OSError, ValueError) as exc:
        print(f'identify: error: {exc}', file=sys.stderr)
        return 1
    rec = run.record
    T = run.dt_ns * 1e-9
    settings = StructureSettings(fit=FitSettings(max_delay=args.max_delay))
    structures = structure_record(rec, T, axes, args.skip, settings)
    chosen = {a: m for a, (m, _, _) in structures.items()}
    print(f'{args.bag}: {len(rec.t)} samples at T = {1e3 * T:g} ms, from t = {args.skip:g} s')
    print(structure_table(chosen, args.pitch))
    failed = [m.line(a) for a, m in chosen.items() if m.model == NONE]
    for line in failed:
        print(f'identify: {line}', file=sys.stderr)
    if failed:
        print('identify: no machine model written', file=sys.stderr)
        return 1
    fits = {
        a: (m.fit, x, u)
        for a, (m, x, u) in structures.items()
        if m.model in (RIGID, TWO_MASS) and m.fit is not None
    }
    models = {a: f[0] for a, f in fits.items()}
    run_dir = Path(args.bag).resolve().parent
    out = args.output or run_dir / 'machine.yaml'
    picture = args.plot or run_dir / 'identify.png'
    if models:
        print(table(models, args.pitch))
    machine_file.write(out, machine_file.MachineModel(T, models, str(args.bag), chosen))
    if fits:
        plot(picture, fits)
        print(f'plot: {picture}')
    print(f'machine model: {out}')
    others = [a for a in chosen if a not in models]
    if others:
        print(
            f'tune cannot design for {", ".join(others)}: a two-mass model without the rigid '
            f'fit at its delay (its gain, friction and load)'
        )
    else:
        print(f'next: tune {out} (docs/bring-up.md)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
