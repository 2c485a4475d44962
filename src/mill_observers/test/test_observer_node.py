"""The observer node in this process: a run-time change of a bandwidth or gain that its
observer cannot be built or run with is refused in one line, and the observer that runs
goes on (issue 37), also when the change is of an observer that does not run."""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from mill_common.in_process import node_factory, set_one


@pytest.fixture
def observer(monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[..., Any]]:
    """observer(*ros_args) -> a ObserverNode `x_observer` in a context of its own."""
    from mill_observers.observer_node import ObserverNode

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(150 + os.getpid() % 10))
    with node_factory(ObserverNode, 'x_observer') as make:
        yield make


@pytest.mark.parametrize(
    ('observer_name', 'name', 'value', 'why'),
    [
        ('dfo', 'dfo.omega_o', 1e300, 'OverflowError'),
        ('dfo', 'dfo.omega_o', 1e-300, 'FloatingPointError: divide by zero'),
        ('gpi', 'gpi.zeta_o', 1e300, 'estimates Estimate(position=nan'),
        ('imbdo_dfo', 'imbdo_dfo.omega_o', 1e300, 'OverflowError'),
    ],
)
def test_a_bandwidth_the_observer_cannot_be_built_with_is_refused_running_or_not(
    observer, observer_name: str, name: str, value: float, why: str
) -> None:
    other = 'eso' if observer_name != 'eso' else 'gpi'
    for running in (other, observer_name):
        node = observer('-p', f'observer:={running}')
        loop, values = node._loop, dict(node.params.values)
        result = set_one(node, name, value)
        assert not result.successful and '\n' not in result.reason
        assert result.reason.startswith(f'{name}={value!r}: ') and why in result.reason
        assert ('(not the running observer)' in result.reason) is (running != observer_name)
        assert node._loop is loop and node.params.values == values
        assert node.get_parameter(name).value == values[name]
        # it runs on: an estimate of the same observer, finite
        est = node._loop.step(1e-3, None)
        assert all(math.isfinite(v) for v in (est.position, est.velocity, est.disturbance))
        assert set_one(node, 'blend_time', 0.01).successful


def test_a_bad_bandwidth_given_at_start_up_ends_the_start_up_in_one_line(observer) -> None:
    # Issue 37: every observer given other gains than its defaults is built at start-up.
    from mill_common.ros_params import CoresNotBuilt

    with pytest.raises(CoresNotBuilt) as info:
        observer('-p', 'observer:=imbdo', '-p', 'dfo.omega_o:=1e300')
    assert str(info.value) == (
        "observer='imbdo', dfo.omega_o=1e+300: dfo (not the running observer): "
        "OverflowError: (34, 'Numerical result out of range')"
    )
    node = observer('-p', 'observer:=imbdo', '-p', 'dfo.omega_o:=200.0')
    assert set_one(node, 'observer', 'dfo').successful


def test_an_extreme_bandwidth_that_builds_a_finite_observer_is_taken(observer) -> None:
    # gpi designs its discrete poles at exp(-ω_o T): 1e300 is a deadbeat observer (poles at
    # 0), 1e-300 poles at 1; both finite, both taken, and they estimate finite values.
    node = observer('-p', 'observer:=gpi')
    for value in (1e300, 1e-300):
        assert set_one(node, 'gpi.omega_o', value).successful, value
        est = node._loop.step(1e-3, None)
        assert all(math.isfinite(v) for v in (est.position, est.velocity, est.disturbance))
