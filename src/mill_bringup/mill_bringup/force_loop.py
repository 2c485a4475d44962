"""Offline closed force loop of Rubio 2013 (issue #4), ROS-free.

Per sample k (t_k = kT, T = one spindle revolution):

1. the measured peak force F_p,k; a non-finite sample is replaced by the last finite one;
2. the controller (fixed β, scheme 1 or scheme 2) gets the known depth a_dc(t_k) and
   returns the feed command f_c,k [mm/s];
3. the feed override o_k = f_c,k / nominal_feed is clamped to [override_min,
   override_max] (a non-finite one holds the last applied override); the applied feed
   o_k·nominal_feed is reported back to the controller (its memory uses what was applied);
4. the plant sees the active β-hold reconstruction u_k + β(u_k − u_{k−1})τ/T, itself
   clamped to the feed range, integrated exactly (mill_models.force_process,
   mill_plant.force_drive).

The continuous-time cost eq. (14), J_c = Σ_j ∫_{(j−1)T}^{jT} (F_p(τ) − F_pm(τ))² dτ [N²·s],
compares the continuous force with the continuous response F_pm of eq. (7) to the
continuous reference (the step F_r = 1200 N at t = 0), on a grid of T/32 per sample
(Simpson, split at depth changes and clamp corners).

Run: python -m mill_bringup.force_loop [--plot froh_cost.png] [--depth-profile 0,2,2,3,...]

Whether a scheme beats the ZOH depends on the job: the gain of negative β and of scheme 1
comes from the depth steps. `--depth-profile` runs the sweep and the claims on another
piecewise-constant depth of cut (flat list of start time [s], depth [mm] pairs).
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from mill_analysis.force_record import ForceRecord
from mill_analysis.papers import rubio_claims
from mill_common.declared import ParamSet, param
from mill_common.one_line_parser import OneLineParser
from mill_common.parameters import number, positive, whole_in
from mill_controllers.force_control import ForceFeedLoop, ForceLaw, build_law
from mill_models.force_process import ForceProcessModel, ForceProcessParams, ForceProcessPlant
from mill_models.quadrature import simpson
from mill_models.reference_model import ContinuousReference
from mill_plant.force_drive import DrivenForceProcess

from mill_bringup.simulation import run_samples


def _number_or_inf(value: Any) -> str | None:
    if isinstance(value, int | float) and not isinstance(value, bool) and math.isinf(value):
        return None
    return number(value)


@dataclass(frozen=True)
class ForceLoopParams(ParamSet):
    """The offline force job's own settings (the Rubio 2013 experiment)."""

    PREFIX: ClassVar[str] = 'force_loop'
    reference_force: float = param(
        1200.0, 'reference peak force F_r (Rubio 2013 §5)', positive, unit='N'
    )
    job_duration: float = param(10.0, 'simulated job length', positive, unit='s')
    nominal_feed: float = param(
        10.0, 'programmed path speed the feed override multiplies', positive, unit='mm/s'
    )
    override_min: float = param(
        0.0, 'lowest feed override (0: never reverse)', _number_or_inf, unit='-'
    )
    override_max: float = param(2.0, 'highest feed override (200 %)', _number_or_inf, unit='-')
    intersample_intervals: int = param(
        32, 'grid intervals per sample for J_c', whole_in(1, 1000), unit='-'
    )


def loop_values(values: Mapping[str, Any] | None = None) -> ForceLoopParams:
    return ForceLoopParams.from_values(dict(values or {}))


def make_controller(
    kind: str,
    model: ForceProcessModel,
    loop: Mapping[str, Any] | None = None,
    values: Mapping[str, Any] | None = None,
) -> ForceLaw:
    """'fixed' (values['beta']), 'scheme1' or 'scheme2', with the loop's feed range."""
    lv = loop_values(loop)
    lo = lv.override_min * lv.nominal_feed
    hi = lv.override_max * lv.nominal_feed
    return build_law(kind, model, dict(values or {}), lo, hi)


class _Corrupted:
    """A law whose feed command is replaced at chosen samples (tests of the clamp/hold)."""

    def __init__(self, law: ForceLaw, overrides: Mapping[int, float], nominal: float) -> None:
        self.law = law
        self.designer = law.designer
        self.overrides = dict(overrides)
        self.nominal = nominal
        self.k = 0

    @property
    def active_beta(self) -> float:
        return self.law.active_beta

    def set_depth(self, depth: float) -> None:
        self.law.set_depth(depth)

    def update(self, force_reference: float, force_measured: float) -> float:
        u = self.law.update(force_reference, force_measured)
        bad = self.overrides.get(self.k)
        self.k += 1
        return u if bad is None else bad * self.nominal

    def record_applied(self, feed: float) -> None:
        self.law.record_applied(feed)


class ForceLoopSimulation:
    """The closed force loop one revolution at a time (see the module doc).

    nan_samples: k whose force measurement is NaN (sensor dropout); override_corruption
    {k: value} replaces the controller's override at k (tests of the clamp/hold path).
    The data flow is the distributed one (mill_bringup.jobs.force): the force sample at
    t_k, the override o_k and its β-hold slope, the drive's clamped feed, the next sample.
    """

    def __init__(
        self,
        controller: ForceLaw,
        model: ForceProcessModel,
        loop: Mapping[str, Any] | None = None,
        nan_samples: Sequence[int] = (),
        override_corruption: Mapping[int, float] | None = None,
        keep_trace: bool = False,
    ) -> None:
        lv = loop_values(loop)
        T = model.sample_period
        self.samples = max(1, math.ceil(lv.job_duration / T - 1e-9))
        self.nominal = lv.nominal_feed
        o_lo, o_hi = lv.override_min, lv.override_max
        if not o_lo <= o_hi:
            raise ValueError(f'override range [{o_lo}, {o_hi}] is empty')
        if override_corruption:
            controller = _Corrupted(controller, override_corruption, self.nominal)
        self.model = model
        self.period = T
        self.feed_loop = ForceFeedLoop(controller, model, self.nominal, o_lo, o_hi)
        self.drive = DrivenForceProcess(
            ForceProcessPlant(model),
            o_lo * self.nominal,
            o_hi * self.nominal,
            T / lv.intersample_intervals,
        )
        # J_c compares with the law's own reference model eq. (7)
        self.f_ref = ContinuousReference(controller.designer.damping, controller.designer.omega_n)
        self.nan_set = set(nan_samples)
        self.reference = lv.reference_force
        self.keep_trace = keep_trace
        self.rec = ForceRecord.empty(self.samples, T)
        self.rec.feed = np.full(self.samples, np.nan)
        self.rec.interval_cost = np.full(self.samples, np.nan)
        self.rec.measured = np.full(self.samples, np.nan)
        self.trace: list[tuple[np.ndarray, np.ndarray]] = []

    def step(self, k: int) -> None:
        rec, drive = self.rec, self.drive
        assert rec.feed is not None and rec.measured is not None  # offline arrays, made above
        assert rec.interval_cost is not None
        t = drive.plant.time
        measured = math.nan if k in self.nan_set else drive.plant.force
        cmd = self.feed_loop.step(t, self.reference, measured)
        feed = cmd.override * self.nominal
        self.f_ref.begin(self.reference)
        cost = 0.0
        for times, force in drive.apply(feed, cmd.slope * self.nominal, self.period):
            f_pm = self.f_ref.values(times)
            cost += simpson(times, (force - f_pm) ** 2)
            if self.keep_trace:
                rec.fine.append((times, force, f_pm))
                self.trace.append((times, force))
        self.f_ref.advance(self.period)
        rec.reference[k] = self.reference
        rec.measured[k] = measured
        rec.force[k] = cmd.force
        rec.feed_command[k] = cmd.feed_command
        rec.feed[k] = feed
        rec.override[k] = cmd.override
        rec.slope[k] = cmd.slope
        rec.beta[k] = cmd.beta
        rec.depth[k] = self.model.depth_at(t)
        rec.interval_cost[k] = cost

    def finished(self) -> bool:
        return False  # the job is a whole number of revolutions, known in advance

    def record(self) -> ForceRecord:
        rec = self.rec
        rec.held_samples = self.feed_loop.held_samples
        assert rec.interval_cost is not None  # made in __init__
        rec.j_c = float(np.sum(rec.interval_cost))
        if self.trace:
            rec.trace_ns = np.concatenate(
                [np.rint(t * 1e9).astype(np.int64) for t, _ in self.trace]
            )
            rec.trace_force = np.concatenate([f for _, f in self.trace])
        return rec


def simulate(
    controller: ForceLaw,
    model: ForceProcessModel,
    loop: Mapping[str, Any] | None = None,
    nan_samples: Sequence[int] = (),
    override_corruption: Mapping[int, float] | None = None,
    keep_trace: bool = False,
) -> ForceRecord:
    """Run the whole job offline (ForceLoopSimulation through the one offline loop)."""
    sim = ForceLoopSimulation(controller, model, loop, nan_samples, override_corruption, keep_trace)
    return run_samples(sim, sim.samples)


def run(
    kind: str,
    beta: float = 0.0,
    model: ForceProcessModel | None = None,
    loop: Mapping[str, Any] | None = None,
    values: Mapping[str, Any] | None = None,
    keep_trace: bool = False,
) -> ForceRecord:
    model = model or ForceProcessModel()
    values = dict(values or {})
    if kind == 'fixed':
        values.setdefault('beta', beta)
    ctrl = make_controller(kind, model, loop, values)
    return simulate(ctrl, model, loop, keep_trace=keep_trace)


def sweep(
    betas: Sequence[float] | np.ndarray,
    model: ForceProcessModel | None = None,
    loop: Mapping[str, Any] | None = None,
    values: Mapping[str, Any] | None = None,
) -> np.ndarray:
    """J_c [N²·s] of the fixed-β loop for each β."""
    return np.array([run('fixed', b, model, loop, values).j_c for b in betas])


PAPER_CASES: dict[str, tuple[str, float]] = {
    'ZOH (β = 0)': ('fixed', 0.0),
    'β = −0.3': ('fixed', -0.3),
    'scheme 1': ('scheme1', 0.0),
    'scheme 2': ('scheme2', 0.0),
}


def paper_cases(
    model: ForceProcessModel | None = None,
    loop: Mapping[str, Any] | None = None,
    scheme_values: Mapping[str, Any] | None = None,
) -> dict[str, ForceRecord]:
    """The four runs of Rubio 2013 §5 on the same job."""
    out = {}
    for name, (kind, beta) in PAPER_CASES.items():
        values = None if kind == 'fixed' else scheme_values
        out[name] = run(kind, beta, model, loop, values)
    return out


def plot_cost_vs_beta(
    betas: Sequence[float] | np.ndarray,
    costs: Sequence[float] | np.ndarray,
    path: str,
    marks: Mapping[str, float] | None = None,
    title: str = 'Continuous-time cost J_c vs β (cf. Rubio 2013 fig. 10)',
) -> None:
    """J_c vs β as a PNG; marks {label: J_c} (e.g. the schemes) are horizontal lines."""
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.0, 4.5))
    ax.plot(betas, costs, 'o-', color='tab:blue', label='fixed β-FROH')
    colors = ['tab:red', 'tab:green', 'tab:orange', 'tab:purple']
    for i, (label, value) in enumerate((marks or {}).items()):
        ax.axhline(value, color=colors[i % 4], lw=1.2, ls='--', label=f'{label}: {value:.6g}')
    ax.set_xlabel('hold gain β [-]')
    ax.set_ylabel('J_c [N²·s]')
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _table(rows: Sequence[tuple[str, str]]) -> str:
    w = max(len(a) for a, _ in rows)
    return '\n'.join(f'{a:<{w}}  {b}' for a, b in rows)


def _profile(text: str) -> list[float] | None:
    try:
        values = [float(v) for v in text.replace(',', ' ').split()]
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text!r} is not a list of numbers') from None
    return values


def main(argv: Sequence[str] | None = None, out: Callable[[str], None] = print) -> int:
    parser = OneLineParser(
        prog='python -m mill_bringup.force_loop', description=__doc__.split('\n')[0]
    )
    parser.add_argument('--plot', default='', help='write the J_c vs β plot to this PNG')
    parser.add_argument('--step', type=float, default=0.1, help='β step of the sweep')
    parser.add_argument(
        '--unclamped', action='store_true', help='no override range (the paper has none)'
    )
    parser.add_argument(
        '--depth-profile',
        type=_profile,
        metavar='T0,A0,T1,A1,...',
        help='axial depth of cut: start times [s] from 0 and depths [mm], piecewise constant '
        '(default: ours, 2,3,1.5,3.5,2 mm from 0,2,4,6,8 s)',
    )
    args = parser.parse_args(argv)
    try:
        given = {} if args.depth_profile is None else {'depth_profile': args.depth_profile}
        model = ForceProcessModel(ForceProcessParams(**given))
    except ValueError as exc:
        parser.error(f'--depth-profile: {exc}')
    loop = {'override_min': -math.inf, 'override_max': math.inf} if args.unclamped else {}
    betas = np.round(np.arange(-1.0, 1.0 + 1e-9, args.step), 10)
    depths = ', '.join(f'{a:g} mm from {t:g} s' for t, a in model.depth_profile)
    out(f'depth of cut: {depths}')
    costs = sweep(betas, model=model, loop=loop)
    rows = [(f'{b:+.2f}', f'{c:.6g}') for b, c in zip(betas, costs, strict=True)]
    out(_table([('β', 'J_c [N²·s]'), *rows]))
    cases = paper_cases(model=model, loop=loop)
    out('')
    out(_table([(name, f'J_c = {rec.j_c:.6g}') for name, rec in cases.items()]))
    out('')
    out(rubio_claims(dict(zip(betas.tolist(), costs.tolist(), strict=True)), cases))
    if args.plot:
        marks = {name: cases[name].j_c for name in ('ZOH (β = 0)', 'scheme 1', 'scheme 2')}
        plot_cost_vs_beta(betas, costs, args.plot, marks)
        out(f'plot: {args.plot}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
