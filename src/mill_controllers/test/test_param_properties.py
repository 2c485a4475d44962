"""Property tests (hypothesis): no parameter set and no law switch kills a controller node.

Every declared parameter of every law of the registry (and `controller` itself, the
switch) is set in sequences to values drawn from its spec (mill_common.param_examples:
accepted ones, edges, refused ones, and any float for a double) on one in-process node, as
`ros2 param set` would. After each change: the node is alive and answers; a refused change
left the values, the ROS parameter and the running law as they were, with a one-line
reason; an accepted one runs a control loop that commands finite values on an axis 1 mm
from its reference, until a trip (issue 37, point 4). The node's other run-time parameters
are drawn too.
"""

from __future__ import annotations

import copy
import math
import os
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from mill_common.in_process import node_factory, set_one
from mill_common.param_examples import examples
from mill_common.parameters import ParamSpec, value_type
from mill_common.signals import AxisReference, Estimate
from mill_controllers.config import parameter_specs
from mill_controllers.registry import CONTROLLERS

SPECS = dict(parameter_specs())
# Every law's parameters, from the registry, the switch between the laws, and the node's
# other parameters that may change at run time (command shaping, blend, trip limit).
LAWS = ['controller', *(name for name, _spec in CONTROLLERS.parameter_specs())]
NAMES = LAWS + [n for n, s in SPECS.items() if n not in LAWS and not s.read_only]
SAMPLES = 40


@pytest.fixture
def controller(monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[..., Any]]:
    from mill_controllers.axis_controller_node import AxisControllerNode

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(150 + os.getpid() % 10))
    with node_factory(AxisControllerNode, 'x_controller') as make:
        yield make


def test_the_names_come_from_the_registry() -> None:
    assert len(LAWS) > 40 and {'gpi.omega_n', 'sliding_gpi.omega_n', 'pd.omega_c'} <= set(LAWS)
    assert {'blend_time', 'following_error_limit'} <= set(NAMES)
    assert all(name in SPECS for name in NAMES)


class Reference:
    """A reference 1 mm from the axis, moving 0.1 mm/s."""

    def at(self, ns: int) -> AxisReference:
        return AxisReference(1e-3 + 1e-4 * ns * 1e-9, 1e-4, 0.0)


def commands(loop: Any, sample_period: float) -> list[float]:
    """What a copy of the node's control loop (law, command shaping, trip) commands over
    SAMPLES samples, the axis at rest (the integrators wind up: the gains act on a growing
    sum), up to a trip (a limit set below 1 mm trips at once: NaN, the brake request)."""
    trial = copy.deepcopy(loop)
    out = []
    for k in range(SAMPLES):
        command = trial.step(
            round(k * sample_period * 1e9), 0.0, Estimate(0.0, 0.0, 0.0), Reference()
        )
        if trial.trip.tripped:
            break
        out.append(command.effort)
    return out


def values(spec: ParamSpec) -> Any:
    """The spec's examples (accepted, edges, refused), and any float for a double."""
    drawn = st.sampled_from(examples(spec))
    if value_type(spec) == 'double':
        return st.one_of(drawn, st.floats(allow_nan=True, allow_infinity=True))
    return drawn


def changes() -> Any:
    """Sequences of (name, value), a law switch among them as often as a gain."""
    name = st.one_of(st.just('controller'), st.sampled_from(NAMES))
    change = name.flatmap(lambda n: st.tuples(st.just(n), values(SPECS[n])))
    return st.lists(change, min_size=1, max_size=6)


def test_no_sequence_of_changes_kills_the_node_or_its_law(controller) -> None:
    node = controller()
    refusals = []

    @settings(
        max_examples=40,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )
    @given(changes())
    @example([('gpi.omega_n', 1e300), ('controller', 'gpi')])  # issue 37's two sets
    @example([('sliding_gpi.omega_n', 1e300), ('controller', 'sliding_gpi')])
    def run(sequence: list[tuple[str, Any]]) -> None:
        for name, value in sequence:
            law, before = node.loop.law, dict(node.params.values)
            result = set_one(node, name, value)
            if not result.successful:
                refusals.append(result.reason)
                assert result.reason and '\n' not in result.reason, result.reason
                assert node.loop.law is law and node.params.values == before
                assert node.get_parameter(name).value == before[name]
                continue
            v = node.params.values
            if v['controller'] == 'adaptive_pi' and v['adaptive_pi.model_source'] == 'observer':
                continue  # it needs the rls observer's model each sample: not here
            u = commands(node.loop, v['sample_period'])
            assert all(math.isfinite(x) for x in u), (name, value, u)

    run()
    assert refusals  # the strategies draw refused values too
    assert set_one(node, 'controller', 'pd').successful  # and the node takes changes still
