"""The text of a report: the table printed on stdout and the Markdown of report.md."""

from __future__ import annotations

import datetime as dt
import math

import numpy as np

from mill_analysis.report.analysis import RunReport


def _um(x: float) -> str:
    return f'{x * 1e6:.3f}' if math.isfinite(x) else 'n/a'


def _f(x: float, fmt: str = '.3f') -> str:
    return format(x, fmt) if x is not None and math.isfinite(x) else 'n/a'


def hz(f: float) -> str:
    """A frequency as the report labels it: 60 Hz."""
    return f'{f:g} Hz'


def text_table(reports: list[RunReport]) -> str:
    lines = []
    for r in reports:
        lines.append(
            f'== {r.label}: {r.run.bag.path} ({r.run.extent()}, T = {r.run.dt_ns / 1e6:g} ms)'
        )
        if r.figures is not None:  # the runner's summary block, printed by the same code
            lines += r.figures.figure_lines()
            lines += [e.text() for e in r.figures.events]
        head = f'axis   max RMS_{r.window:g}s e [um]'
        for f in r.freqs:
            head += f'   |E({hz(f)})| [um]'
        head += '   RMS tau [N m]   mean F [N]   max |F| [N]'
        lines.append(head)
        for a in r.axes:
            row = f'{a.axis:>4}   {_um(a.max_window_rms_error):>19}'
            for f in r.freqs:
                row += f'   {_um(a.error_amplitude[f]):>{len(hz(f)) + 9}}'
            row += (
                f'   {_f(a.rms_torque, ".4f"):>13}   {_f(a.force_mean, ".2f"):>10}'
                f'   {_f(a.force_max, ".2f"):>11}'
            )
            lines.append(row)
        lines.append(feed_text(r))
        lines.append(loop_text(r))
        if r.run.realtime:
            lines.append(realtime_text(r))
        lines += r.run.losses()
        for note in r.run.notes:
            lines.append(f'note: {note}')
    return '\n'.join(lines)


def feed_text(r: RunReport) -> str:
    if r.feed is None:
        return 'feed override: no feed override in this bag'
    f = r.feed
    return (
        f'feed override: {f["messages"]:.0f} messages, min {f["min"]:.3f}, '
        f'mean {f["mean"]:.3f}, max {f["max"]:.3f}'
    )


def realtime_text(r: RunReport) -> str:
    """Per axis: states no command answered, and state -> command latency as recorded."""
    rows = [
        'realtime: axis   states without a command   in a row   '
        'latency as recorded [ms]: median   p99     max'
    ]
    for axis in r.run.axes:
        lat = r.run.command_latency_ms.get(axis, np.zeros(0))
        med, p99, top = (
            (float(np.median(lat)), float(np.percentile(lat, 99)), float(lat.max()))
            if lat.size
            else (float('nan'),) * 3
        )
        share = 100 * r.run.unanswered.get(axis, float('nan'))
        run = r.run.longest_unanswered.get(axis, 0)
        rows.append(f'{axis:>14}   {share:22.2f} %   {run:8d}   {med:31.3f} {p99:7.3f} {top:7.3f}')
    status = r.run.plant_status
    drive = [
        f'{a}: {100 * float(status[f"{a}.late_fraction"]):.2f} % late'
        + (f' ({status[key]} in a row)' if (key := f'{a}.longest_late_run') in status else '')
        for a in r.run.axes
        if f'{a}.late_fraction' in status
    ]
    if drive:
        rows.append('the drive counted periods without a fresh command: ' + ', '.join(drive))
    return '\n'.join(rows)


def loop_text(r: RunReport) -> str:
    lp = r.loop
    parts = []
    if 'period_mean_ms' in lp:
        parts.append(
            f'sample period (wall) mean {lp["period_mean_ms"]:.3f} ms, jitter (std) '
            f'{lp["period_std_ms"]:.3f} ms, p99 {lp["period_p99_ms"]:.3f} ms, '
            f'max {lp["period_max_ms"]:.1f} ms ({lp["steps_per_second"]:.0f} steps/s)'
        )
    else:
        parts.append('no wall-clock receive times in this bag')
    if 'wait_mean_ms' in lp:
        parts.append(
            f'lockstep wait for commands mean {lp["wait_mean_ms"]:.3f} ms, '
            f'max {lp["wait_max_ms"]:.1f} ms'
        )
    return 'loop timing: ' + '; '.join(parts)


def markdown(reports: list[RunReport], figures: list[tuple[str, str]], argv: list[str]) -> str:
    skip, window, freqs = reports[0].skip, reports[0].window, reports[0].freqs
    out = [
        '# mill run report',
        '',
        f'`report {" ".join(argv)}` on {dt.datetime.now():%Y-%m-%d %H:%M}. '
        f'Metrics over t ≥ {skip:g} s (the start transient excluded); e = measured position − '
        'reference; ξ is the lumped disturbance of Beltrán 2013 eq. (5), ξ̂ its estimate.',
        '',
        '## Bags',
        '',
        '| run | bag | samples | T | machine time | messages | size | per simulated second |'
        ' samples from |',
        '|---|---|---|---|---|---|---|---|---|',
    ]
    for r in reports:
        run = r.run
        held, last = run.held
        sim = last if held else math.nan  # what the bag holds of the job
        samples = f'{held}' if held == run.n else f'{held} of {run.n}'
        per_s = run.size_bytes / sim / 1e6 if sim > 0 else math.nan
        out.append(
            f'| {r.label} | `{run.bag.path}` | {samples} | {run.dt_ns / 1e6:g} ms | {sim:.3f} s '
            f'| {run.message_count} | {run.size_bytes / 1e6:.1f} MB | {per_s:.2f} MB '
            f'| {run.job_end_source} |'
        )
    notes = [(r.label, n) for r in reports for n in [*r.run.losses(), *r.run.notes]]
    if notes:
        out.append('')
        out += [f'- {label}: {note}' for label, note in notes]
    out += [
        '',
        '## Tracking and disturbance estimation',
        '',
        f'| run | axis | max \\|e\\| [µm] | RMS e [µm] | max RMS e over {window:g} s [µm] '
        '| RMS(ξ̂−ξ) [m/s²] | max \\|ξ̂−ξ\\| [m/s²] | RMS ξ [m/s²] |',
        '|---|---|---|---|---|---|---|---|',
    ]
    for r in reports:
        for a in r.axes:
            m = a.summary
            out.append(
                f'| {r.label} | {a.axis} | {_um(m.max_error)} | {_um(m.rms_error)} '
                f'| {_um(a.max_window_rms_error)} | {_f(m.rms_disturbance_error)} '
                f'| {_f(a.max_disturbance_error)} | {_f(m.rms_disturbance)} |'
            )
    out += [
        '',
        '## Contour error',
        '',
        'The distance from each measured position to the programmed path (the polyline '
        "through the reference positions, in the space of the run's axes): how far the cut "
        "lies from the part's contour, whatever the lag along the path.",
        '',
        '| run | path | max contour error [µm] | RMS contour error [µm] |',
        '|---|---|---|---|',
    ]
    for r in reports:
        c = r.contour_summary
        if c is not None:
            out.append(
                f'| {r.label} | {"-".join(c.axes)} | {_um(c.max_error)} | {_um(c.rms_error)} |'
            )
    out += [
        '',
        '## Error spectrum',
        '',
        'Amplitude of the tracking error and of the disturbance estimation error at the '
        'chosen frequencies (Hann window, single-frequency DFT over the analysed interval).',
        '',
        '| run | axis | '
        + ' | '.join(f'\\|E({hz(f)})\\| [µm]' for f in freqs)
        + ' | '
        + ' | '.join(f'\\|(ξ̂−ξ)({hz(f)})\\| [m/s²]' for f in freqs)
        + ' |',
        '|---|---|' + '---|' * (2 * len(freqs)),
    ]
    for r in reports:
        for a in r.axes:
            out.append(
                f'| {r.label} | {a.axis} | '
                + ' | '.join(_um(a.error_amplitude[f]) for f in freqs)
                + ' | '
                + ' | '.join(_f(a.disturbance_error_amplitude[f]) for f in freqs)
                + ' |'
            )
    out += [
        '',
        '## Cutting force and commanded torque',
        '',
        '| run | axis | mean F [N] | std F [N] | max \\|F\\| [N] | RMS τ [N·m] '
        '| max \\|τ\\| [N·m] |',
        '|---|---|---|---|---|---|---|',
    ]
    for r in reports:
        for a in r.axes:
            out.append(
                f'| {r.label} | {a.axis} | {_f(a.force_mean, ".2f")} | {_f(a.force_std, ".2f")} '
                f'| {_f(a.force_max, ".2f")} | {_f(a.rms_torque, ".4f")} '
                f'| {_f(a.max_torque, ".4f")} |'
            )
    out += ['', '## Feed override', '']
    out += [f'- {r.label}: {feed_text(r).removeprefix("feed override: ")}' for r in reports]
    out += [
        '',
        '## Loop timing',
        '',
        'Sample period: wall-clock time between the arrivals of consecutive samples of the '
        'first state topic at the recorder (MCAP publish time); jitter is its standard '
        'deviation. Lockstep wait: the time the plant waited for all commands of a step '
        '(its /diagnostics status).',
        '',
        '| run | mean period [ms] | jitter [ms] | p99 [ms] | max [ms] | steps/s '
        '| mean wait [ms] | max wait [ms] |',
        '|---|---|---|---|---|---|---|---|',
    ]
    for r in reports:
        lp = r.loop
        out.append(
            f'| {r.label} | {_f(lp.get("period_mean_ms", math.nan))} '
            f'| {_f(lp.get("period_std_ms", math.nan))} | {_f(lp.get("period_p99_ms", math.nan))} '
            f'| {_f(lp.get("period_max_ms", math.nan), ".1f")} '
            f'| {_f(lp.get("steps_per_second", math.nan), ".0f")} '
            f'| {_f(lp.get("wait_mean_ms", math.nan))} '
            f'| {_f(lp.get("wait_max_ms", math.nan), ".1f")} |'
        )
    out += ['', '## Figures', '']
    for name, caption in figures:
        out += [f'### {caption}', '', f'![{caption}]({name})', '']
    return '\n'.join(out)
