"""Every figure of the docs: its id → the group (command) that prints it.

A group runs what its figures need once (runs.py caches the offline runs) and returns
{key: text}; the figure's id is `GROUP.KEY`. `command` is what a reader runs to see the
same figures in context. A group that starts ROS processes is `system`: its check runs in
the system phase of the tests.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from mill_bringup.docs_figures import (
    adaptive_feed,
    beltran,
    beltran_model,
    chavez_conde,
    hatwesh,
    maharof,
    rubio,
)


@dataclass(frozen=True)
class Group:
    name: str
    command: str
    figures: Callable[[], dict[str, str]]  # key -> the figure as the docs print it
    system: bool = False  # needs ROS processes (run_scenario)


GROUPS = {
    g.name: g
    for g in (
        Group('beltran', 'offline_sim beltran', beltran.figures),
        Group(
            'beltran_discretisation',
            "offline_sim beltran --variant adrc -p '*_observer.gpi.discretisation=NAME'",
            beltran.discretisation_figures,
        ),
        Group(
            'beltran_specific_energy',
            'offline_sim beltran --variant adrc -p plant.kline.specific_energy=3.0e10'
            ' (and --variant pd -p plant.speed_limit=5.0)',
            beltran.specific_energy_figures,
        ),
        Group(
            'beltran_model',
            'docs_figures --group beltran_model (the model and the cores, no run)',
            beltran_model.figures,
        ),
        Group(
            'beltran_step',
            "offline_sim slotting -p plant.cutting_model=step -p 'plant.step.force=[100.0,0.0,0.0]'"
            ' -p plant.step.start_time=1.0 -p trajectory.duration=1.2 (and y, z)',
            beltran.step_figures,
        ),
        Group('chavez_conde', 'offline_sim chavez_conde --skip 0', chavez_conde.figures),
        Group(
            'chavez_conde_probes',
            "offline_sim chavez_conde --skip 0 --variant sliding_gpi -p '*.sample_period=0.00005'"
            ' (and the other overrides docs/papers.md names)',
            chavez_conde.probe_figures,
        ),
        Group('maharof', 'offline_sim maharof', maharof.figures),
        Group(
            'hatwesh_margins', 'python -m mill_controllers.hatwesh_margins', hatwesh.margin_figures
        ),
        Group(
            'hatwesh_velocity',
            'offline_sim hatwesh_velocity --skip 0 [-p x_controller.adaptive_pi.load_term=false'
            ' | -p x_controller.adaptive_pi.design_rule=discrete]',
            hatwesh.velocity_figures,
        ),
        Group(
            'hatwesh',
            'offline_sim hatwesh --skip 0 [--variant adaptive_pi'
            ' -p x_controller.adaptive_pi.phase_margin=25.0]',
            hatwesh.move_figures,
        ),
        Group(
            'adaptive_feed',
            'offline_sim slotting_adaptive_feed [-p force_controller.force_process.immersion=1.8]',
            adaptive_feed.figures,
        ),
        Group(
            'rubio',
            'offline_sim rubio; python -m mill_bringup.force_loop [--depth-profile ...]',
            rubio.figures,
        ),
    )
}


def compute(name: str) -> dict[str, str]:
    """The figures of group `name`, by id."""
    return {f'{name}.{k}': v for k, v in GROUPS[name].figures().items()}


def group_of(figure_id: str) -> str:
    return figure_id.split('.', 1)[0]


@dataclass(frozen=True)
class Measured:
    """Figures the check leaves out on purpose: timings (wall time, steps/s, memory), which
    depend on the machine. The docs state the command and the machine or date beside them;
    `text` is a phrase of the document that must stay there (a test), so this list and the
    docs cannot drift apart."""

    document: str
    text: str
    how: str


MEASURED = (
    Measured(
        'README.md',
        '## How fast it runs',
        'the whole section: `benchmark commissioning ...` on the 2-core machine, 3 December 2026',
    ),
    Measured('docs/papers.md', '`offline_sim beltran` (about 10 s of CPU per variant)', 'CPU'),
    Measured('docs/papers.md', '(22 variants, 12 minutes on the', 'wall time'),
    Measured(
        'docs/papers.md',
        '`offline_sim maharof` (about 2 s of wall time per configuration)',
        'wall time',
    ),
    Measured('docs/papers.md', 'took 25 s at 0.1 ms sampling (1610 steps/s', 'wall time, steps/s'),
    Measured('docs/architecture.md', 'CPU per group', 'CPU of each group of this check'),
)
