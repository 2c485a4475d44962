"""Parameters of the drive front end (timing, watchdog, owners), as data. ROS-free."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from mill_common.declared import ParamSet, param
from mill_common.hold_window import HoldWindow
from mill_common.node_params import RealtimeScheduling
from mill_common.parameters import (
    ParamSpec,
    boolean,
    in_range,
    non_negative_int,
    one_of,
    whole_in,
)
from mill_common.travel import MachineTravel

from mill_common import topics
from mill_plant.topic_pair import Ros2ControlParams

TIMINGS = ('lockstep', 'realtime')


def _owners(value: Any) -> str | None:
    if not isinstance(value, list | tuple) or len(value) != 3:
        return 'must list 3 node names (the owners of x, y, z commands)'
    if not all(isinstance(v, str) for v in value):
        return 'must list node names (strings); "" accepts commands from any node'
    return None


@dataclass(frozen=True)
class RecorderWindow(ParamSet):
    """Shared with the force process, the other node that clocks a lockstep run."""

    recorder_window: int = param(
        0,
        'lockstep: steps the plant may run ahead of the newest step the recorder (or '
        f'run_scenario) has acknowledged on {topics.RECORDED}, so that neither a bag nor a '
        "run's record misses a step however busy the machine (run_scenario sets it); 0: do "
        'not wait for a recorder',
        non_negative_int,
        read_only=True,
    )


@dataclass(frozen=True)
class DriveParams(HoldWindow, RealtimeScheduling, RecorderWindow):
    """The drive front end's own parameters (timing, watchdog, owners), whatever its backend."""

    timing: str = param(
        'lockstep',
        'lockstep: the plant is the clock and waits for the commands of each step; '
        'realtime: it advances on the wall clock at the sample rate and applies the newest '
        'command it holds (zero-order hold), as a drive does',
        one_of(*TIMINGS),
        read_only=True,
    )
    command_owners: list[str] = param(
        ['x_controller', 'y_controller', 'z_controller'],
        'the node whose commands each axis x, y, z accepts (its publisher GID in the graph; '
        'header.frame_id must agree); commands from '
        'any other node are ignored and reported; "" accepts any',
        _owners,
        read_only=True,
    )
    command_delay: int = param(
        0,
        'lockstep: samples N between the step a command answers and the step the plant '
        'applies it from (a transport delay; the first N steps get zero input); realtime '
        'has one sample by nature and ignores it; at most 1000, the most the controllers '
        'and observers compensate (their own command_delay, which must equal it)',
        whole_in(0, 1000),
        read_only=True,
    )
    speed_limit: float = param(
        0.5,
        'an axis faster than this over a period is stopped (braked until re-armed), '
        "in real time and in lockstep, whatever its commands [m/s]; set it to the machine's "
        'rapid traverse',
        in_range(1e-4, 100.0),
    )
    joint_states_rate: float = param(
        50.0,
        f'how often the drive publishes {topics.JOINT_STATES} (every axis: measured position, '
        'velocity and the effort applied; for RViz, Foxglove, robot_state_publisher): every '
        'N samples, N the fewest that keep it at or below this rate; 0: not at all',
        in_range(0.0, 100.0),
        unit='Hz',
        read_only=True,
    )
    command_report_time: float = param(
        0.5,
        'wall time without the command an axis waits for before /diagnostics says so',
        in_range(0.01, 60.0),
        unit='s',
    )
    spindle: str = param(
        'on',
        f"on: the machine's spindle always runs (a path that programs none); reference: "
        f"it runs at the speed of the joint 'spindle' of {topics.REFERENCE} (G-code M3/M4/M5 "
        'and S), sample by sample, and is off before the first; lockstep waits for it',
        one_of('on', 'reference'),
        read_only=True,
    )
    autostart: bool = param(
        True,
        'configure and activate by itself (lockstep: once its peers are matched); false: '
        'wait for the lifecycle transitions configure and activate',
        boolean,
        read_only=True,
    )


# The machine's travel (mill_common.travel): the motion guard stops an axis about to leave it;
# ros2_control's topic pair (mill_plant.topic_pair).
DRIVE_PARAMETERS: tuple[tuple[str, ParamSpec], ...] = (
    *DriveParams.named_specs(),
    *((name, replace(spec, name=name)) for name, spec in Ros2ControlParams.named_specs()),
    *((name, replace(spec, name=name)) for name, spec in MachineTravel.named_specs(True)),
)
