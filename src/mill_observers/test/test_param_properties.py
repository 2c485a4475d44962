"""Property tests (hypothesis): no parameter set and no observer switch kills an observer node.

Every declared parameter of every observer of the registry (and `observer` itself, the
switch) is set in sequences to values drawn from its spec (mill_common.param_examples) on
one in-process node, as `ros2 param set` would. After each change: the node is alive and
answers; a refused change left the values, the ROS parameter and the running observer as
they were, with a one-line reason; an accepted one estimates finite values of a moving,
driven axis (issue 37, point 4).
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
from mill_observers.config import parameter_specs
from mill_observers.registry import OBSERVERS

SPECS = dict(parameter_specs())
# Every observer's parameters, from the registry, and the switch between them.
NAMES = ['observer', *(name for name, _spec in OBSERVERS.parameter_specs())]
SAMPLES = 40


@pytest.fixture
def observer(monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[..., Any]]:
    from mill_observers.observer_node import ObserverNode

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(150 + os.getpid() % 10))
    with node_factory(ObserverNode, 'x_observer') as make:
        yield make


def test_the_names_come_from_the_registry() -> None:
    assert len(NAMES) > 40 and {'gpi.omega_o', 'dfo.omega_o', 'rls.forgetting'} <= set(NAMES)
    assert all(name in SPECS for name in NAMES)


def estimates(loop: Any) -> list[float]:
    """What a copy of the loop estimates over SAMPLES samples of an axis moving 1 mm about
    its start, driven by a command of 0.5."""
    trial = copy.deepcopy(loop)
    out: list[float] = []
    acted = None
    for k in range(SAMPLES):
        est = trial.step(1e-3 * math.sin(k / 10), acted)
        acted = 0.5 * math.cos(k / 7)
        out += [est.position, est.velocity, est.disturbance]
    return out


def values(spec: ParamSpec) -> Any:
    """The spec's examples (accepted, edges, refused), and any float for a double."""
    drawn = st.sampled_from(examples(spec))
    if value_type(spec) == 'double':
        return st.one_of(drawn, st.floats(allow_nan=True, allow_infinity=True))
    return drawn


def changes() -> Any:
    name = st.one_of(st.just('observer'), st.sampled_from(NAMES))
    change = name.flatmap(lambda n: st.tuples(st.just(n), values(SPECS[n])))
    return st.lists(change, min_size=1, max_size=6)


def test_no_sequence_of_changes_kills_the_node_or_its_observer(observer) -> None:
    node = observer()
    refusals = []

    @settings(
        max_examples=25,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )
    @given(changes())
    @example([('dfo.omega_o', 1e300), ('observer', 'dfo')])
    @example([('gpi.zeta_o', 1e300), ('observer', 'gpi')])
    def run(sequence: list[tuple[str, Any]]) -> None:
        for name, value in sequence:
            loop, before = node._loop, dict(node.params.values)
            result = set_one(node, name, value)
            if not result.successful:
                refusals.append(result.reason)
                assert result.reason and '\n' not in result.reason, result.reason
                assert node._loop is loop and node.params.values == before
                assert node.get_parameter(name).value == before[name]
                continue
            x = estimates(node._loop)
            assert all(math.isfinite(v) for v in x), (name, value)

    run()
    assert refusals
    assert set_one(node, 'observer', 'eso').successful
