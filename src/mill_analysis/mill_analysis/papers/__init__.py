"""Each paper's own metrics, computed from the runs of a scenario's variants. ROS-free.

A scenario names its paper (`paper:` in its `mill_scenario` entry) and the configurations
it compares (`variants:`); the runner and the offline simulator run every variant and print
`report(paper, records)`: the metrics the paper reports, beside the paper's own figures or
claims, and a verdict per claim that is computed, never written in.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from mill_analysis.chavez_conde import chavez_conde
from mill_analysis.events import BRAKED, STOPPED, TRIP, Event
from mill_analysis.papers.beltran import (
    BELTRAN_BLOCK,
    BELTRAN_COUPLED_DEPTH,
    BELTRAN_EFFECTIVE,
    BELTRAN_FACTOR,
    BELTRAN_FIRST_CUT,
    BELTRAN_K,
    BELTRAN_MEAN_FORCE,
    BELTRAN_PAIRS,
    BELTRAN_WINDOW,
    beltran,
    block_means,
    estimation_errors,
)
from mill_analysis.papers.common import (
    X,
    amplitude,
    verdict,
)
from mill_analysis.papers.hatwesh import (
    HATWESH_BAND,
    HATWESH_MOVES,
    MoveMetrics,
    hatwesh,
    move_metrics,
)
from mill_analysis.papers.hatwesh_velocity import (
    HV_BAND,
    HV_CLAIMS,
    HV_INERTIA_CHANGE,
    HV_LOAD,
    HV_PHASES,
    HV_STEP,
    PhaseMetrics,
    StepMetrics,
    hatwesh_velocity,
    hv_verdicts,
    load_response,
    phase_metrics,
    velocity_steps,
)
from mill_analysis.papers.maharof import (
    MAHAROF_FREQUENCIES,
    MAHAROF_READINGS,
    MAHAROF_TABLES,
    MAHAROF_WINDOW,
    harmonic_cuts,
    maharof,
    maharof_metrics,
)
from mill_analysis.papers.rubio import (
    RUBIO_CASES,
    RUBIO_READINGS,
    RUBIO_SCHEME_CLAIMS,
    rubio,
    rubio_claims,
    rubio_reading_cases,
    rubio_readings,
)
from mill_analysis.papers.settings import (
    READINGS,
    SETTINGS,
    Parameters,
    hatwesh_readings,
    settings_lines,
)

REPORTS: dict[str, Callable[[Mapping[str, Any]], str]] = {
    'beltran': beltran,
    'maharof': maharof,
    'chavez_conde': chavez_conde,
    'hatwesh': hatwesh,
    'hatwesh_velocity': hatwesh_velocity,
    'rubio': rubio,
}


def report(paper: str, records: Mapping[str, Any], parameters: Parameters | None = None) -> str:
    """The paper's metrics of every variant; '' for a scenario without a paper report.

    parameters (variant → node → values): where given, the readings the figures rest on
    come first."""
    fn = REPORTS.get(paper)
    if not fn:
        return ''
    reading = READINGS.get(paper)
    head = reading(parameters) if reading and parameters else ''
    if paper not in OWN_TRIPS:
        head = '\n'.join(filter(None, [head, braked(records)]))
    return f'{head}\n{fn(records)}' if head else fn(records)


# A trip, a stop or a brake: after it an axis is braked, its figures are not the law's.
STOP_KINDS = frozenset({TRIP, STOPPED, BRAKED})

# The reports that give a tripped run its trip themselves, instead of its figures.
OWN_TRIPS = frozenset({'chavez_conde'})


def braked(records: Mapping[str, Any]) -> str:
    """One line per trip or brake a run's record holds: its figures after that are of a
    braked axis, not of the law's tracking."""
    return '\n'.join(
        f'WARNING variant {name}: {event.text()}; its figures after that are of a braked '
        'axis, not of the law'
        for name, rec in records.items()
        for event in getattr(rec, 'events', ())
        if isinstance(event, Event) and event.kind in STOP_KINDS
    )


__all__ = [
    'BELTRAN_BLOCK',
    'BELTRAN_COUPLED_DEPTH',
    'BELTRAN_EFFECTIVE',
    'BELTRAN_FACTOR',
    'BELTRAN_FIRST_CUT',
    'BELTRAN_K',
    'BELTRAN_MEAN_FORCE',
    'BELTRAN_PAIRS',
    'BELTRAN_WINDOW',
    'HATWESH_BAND',
    'HATWESH_MOVES',
    'HV_BAND',
    'HV_CLAIMS',
    'HV_INERTIA_CHANGE',
    'HV_LOAD',
    'HV_PHASES',
    'HV_STEP',
    'MAHAROF_FREQUENCIES',
    'MAHAROF_READINGS',
    'MAHAROF_TABLES',
    'MAHAROF_WINDOW',
    'OWN_TRIPS',
    'READINGS',
    'REPORTS',
    'RUBIO_CASES',
    'RUBIO_READINGS',
    'RUBIO_SCHEME_CLAIMS',
    'SETTINGS',
    'STOP_KINDS',
    'MoveMetrics',
    'Parameters',
    'PhaseMetrics',
    'StepMetrics',
    'X',
    'amplitude',
    'beltran',
    'block_means',
    'braked',
    'chavez_conde',
    'estimation_errors',
    'harmonic_cuts',
    'hatwesh',
    'hatwesh_readings',
    'hatwesh_velocity',
    'hv_verdicts',
    'load_response',
    'maharof',
    'maharof_metrics',
    'move_metrics',
    'phase_metrics',
    'report',
    'rubio',
    'rubio_claims',
    'rubio_reading_cases',
    'rubio_readings',
    'settings_lines',
    'velocity_steps',
    'verdict',
]
