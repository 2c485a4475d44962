"""The job's rules on timing (mill_bringup.job_config): one sample period, gains designed
for the rate the job runs at, one command delay per axis. ROS-free.
"""

from __future__ import annotations

from mill_bringup.job_config_types import Failure, JobConfig, Side, same_period


def one_sample_period(c: JobConfig) -> list[Failure]:
    """Every node that declares sample_period runs at the job's sample period."""
    ref = c.period_source
    out = []
    for n in c.nodes:
        if n.name == ref.node or not n.declares('sample_period'):
            continue
        mine = Side(n.name, 'sample_period', n.values['sample_period'])
        if not same_period(mine.value, ref.value):
            out.append(
                Failure(
                    'sample_period',
                    (ref, mine),
                    f"scenario {c.scenario}: {mine.node}'s sample_period is {mine.value!r} s "
                    f"but {ref.node}'s {ref.name} is {ref.value!r} s: every node of a job runs "
                    'at one sample period (set it once, under /**)',
                )
            )
    return out


def gains_for_the_rate(c: JobConfig) -> list[Failure]:
    """A node's gains designed for one sample period (design_period) run at that period."""
    ref = c.period_source
    out = []
    for n in c.nodes:
        designed = n.values.get('design_period') or 0.0
        if not designed or same_period(designed, ref.value):
            continue
        mine = Side(n.name, 'design_period', designed)
        out.append(
            Failure(
                'design_period',
                (mine, ref),
                f"scenario {c.scenario}: {n.name}'s gains were designed for T = "
                f'{1e3 * designed:g} ms (design_period) but the job runs at T = '
                f"{1e3 * ref.value:g} ms ({ref.node}'s {ref.name}): give gains for this rate, "
                'or the tuning rule (observer eso with eso.omega_o 0, pd.omega_c 0) and '
                'design_period 0',
            )
        )
    return out


def one_command_delay(c: JobConfig) -> list[Failure]:
    """Per axis, the controller aims, the observer predicts and (lockstep) the drive applies
    each command the same samples late. A realtime drive has one sample by nature and
    ignores its command_delay."""
    out = []
    plant = c.plant
    for axis, a in c.axis_configs.items():
        ctrl = Side(a.controller, 'command_delay', c.node(a.controller).values['command_delay'])
        others = [Side(a.observer, 'command_delay', c.node(a.observer).values['command_delay'])]
        if plant is not None and c.timing == 'lockstep':
            others.append(Side(plant, 'command_delay', c.node(plant).values['command_delay']))
        for other in others:
            if other.value != ctrl.value:
                out.append(
                    Failure(
                        'command_delay',
                        (ctrl, other),
                        f'scenario {c.scenario}: axis {axis}: {ctrl.node} has command_delay '
                        f'{ctrl.value} but {other.node} {other.value}: the drive applies each '
                        'command, the observer predicts with it and the controller aims that '
                        'many samples late; give them one (run_scenario --delay N)',
                    )
                )
    return out
