"""The parameters nodes share, declared once as ParamSets (ROS-free).

`input_watch_specs()`, `realtime_specs()` and `axis_node_specs()` give the node configs
that list (name, ParamSpec) pairs the `named_specs()` of the sets here.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

from mill_common.declared import ParamSet, param
from mill_common.parameters import (
    ParamSpec,
    WholeAtLeast,
    in_range,
    non_negative,
    non_negative_int,
    number_list,
    one_of,
    text,
    whole_in,
)
from mill_common.signals import AXES


def _priority(value: Any) -> str | None:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 98:
        return 'must be a whole number from 0 (normal scheduling) to 98'
    return None


class _Cpus:
    """Distinct CPU numbers (a list of whole numbers >= 0, possibly empty)."""

    value_type = 'integer_array'
    text = 'CPU numbers, each once'

    def __call__(self, value: Any) -> str | None:
        problem = number_list(each=WholeAtLeast(0))(value)
        if problem is None and len(set(value)) != len(value):
            return 'must name each CPU once'
        return problem


@dataclass(frozen=True)
class InputWatch(ParamSet):
    """How long a node's inputs may be silent (mill_common.input_guard)."""

    PREFIX: ClassVar[str] = ''
    input_warn_time: float = param(
        1.0,
        'an input silent this long (after its first message) is reported as WARN',
        in_range(0.01, 3600.0),
        unit='s',
    )
    input_timeout: float = param(
        10.0,
        'an input silent this long is an ERROR; in lockstep the node then ends with a '
        'message naming it',
        in_range(0.01, 3600.0),
        unit='s',
    )


@dataclass(frozen=True)
class RealtimeScheduling(ParamSet):
    """The real-time scheduling of a node's process (mill_common.realtime_setup)."""

    PREFIX: ClassVar[str] = ''
    realtime_priority: int = param(
        0,
        "SCHED_FIFO priority of this node's process, every thread (1-98; 0: the normal "
        'scheduler); with it the memory is locked and the garbage collector frozen. The '
        'highest of the nodes of a process counts',
        _priority,
        read_only=True,
    )
    cpu_affinity: list[int] = param(
        [],
        "CPUs this node's process may run on ([]: any); the nodes of a process together",
        _Cpus(),
        read_only=True,
    )


@dataclass(frozen=True)
class AxisNodeParams(InputWatch, RealtimeScheduling):
    """Parameters every per-axis node (controller, observer) has; the input watch and the
    real-time scheduling come first (fields of the bases)."""

    PREFIX: ClassVar[str] = ''
    axis: str = param('x', 'machine axis this node serves', one_of(*AXES), read_only=True)
    input_gain: float = param(
        0.0,
        'b of the nominal model x" = b tau + xi [m/s^2 per N m]; '
        '0 = 1/(a m_e) from Beltrán 2013 Table 1 for this axis',
        non_negative,
    )
    sample_period: float = param(
        0.001, 'sample period T', in_range(1e-6, 1.0), unit='s', read_only=True
    )
    design_period: float = param(
        0.0,
        'the sample period the gains were designed for [s]: at another sample_period '
        'the node refuses to start rather than run them (0: gains for any period, as '
        'the tuning rule gives)',
        non_negative,
        read_only=True,
    )
    timing: str = param(
        'lockstep',
        'lockstep: inputs joined by their exact stamps on the sample grid (the plant is '
        'the clock); realtime: act on the newest state, the reference interpolated at '
        'its stamp, nothing stale queued',
        one_of('lockstep', 'realtime'),
        read_only=True,
    )
    plant_node: str = param(
        'plant',
        'the node whose states this node accepts (its publisher GID in the graph; '
        'header.frame_id must agree); states from any '
        'other node are dropped and reported',
        text,
        read_only=True,
    )
    min_subscribers: int = param(
        0,
        'lockstep: readers the output topic needs before the node answers a step (the '
        'plant offers it again), so that the first outputs of a node started mid-job '
        'reach every reader; run_scenario sets the count of its graph',
        non_negative_int,
    )
    command_delay: int = param(
        0,
        'samples N between the measurement a command is computed from and the period it '
        'acts in (realtime: 1); the observer predicts with the commands that really act '
        'and estimates the state N samples ahead, the controller aims at the reference '
        'N samples ahead',
        whole_in(0, 1000),
        read_only=True,
    )


def input_watch_specs() -> list[tuple[str, ParamSpec]]:
    """How long a node's inputs may be silent (mill_common.input_guard)."""
    return InputWatch.named_specs()


def realtime_specs() -> list[tuple[str, ParamSpec]]:
    """The real-time scheduling of a node's process (mill_common.realtime_setup)."""
    return RealtimeScheduling.named_specs()


def axis_node_specs() -> list[tuple[str, ParamSpec]]:
    """Parameters every per-axis node (controller, observer) has."""
    return AxisNodeParams.named_specs()


def check_design_period(values: Mapping[str, Any] | AxisNodeParams) -> None:
    """ValueError (one line) when gains designed for one sample period would run at another.

    values: a node's values (a mapping) or its typed set (node_params.AxisNodeParams).
    """
    if isinstance(values, Mapping):
        designed, period = values['design_period'], values['sample_period']
    else:
        designed, period = values.design_period, values.sample_period
    if designed and abs(designed - period) > 1e-12 * designed:
        raise ValueError(
            f'the gains were designed for T = {1e3 * designed:g} ms (design_period) and the '
            f'node runs at T = {1e3 * period:g} ms: give gains for this rate, or the tuning '
            'rule (observer eso with eso.omega_o 0, pd.omega_c 0) and design_period 0'
        )
