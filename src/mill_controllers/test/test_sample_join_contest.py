"""A contested input of a sample (two publishers claim its owner's name) stands in for the
input, so the sample is due, and marked to be answered by a brake request; a contested
state stands in for every input of its sample. ROS-free."""

from __future__ import annotations

from mill_common.checks import CONTESTED as CONTESTED_SENDER
from mill_common.checks import FOREIGN
from mill_common.signals import AxisReference, Estimate
from mill_common.timing import timing
from mill_controllers.controller_inputs import CLOCK_INPUT
from mill_controllers.sample_join import CONTESTED, SampleJoin, brakes_on_contest, is_contested

T = 1_000_000


def join() -> SampleJoin:
    j = SampleJoin(timing('lockstep', T), ('position', 'estimate'), 0)
    for k in range(5):
        j.add_reference(k * T, AxisReference(0.0, 0.0, 0.0))
    return j


def test_a_contested_estimate_makes_its_sample_due_and_marked() -> None:
    j = join()
    j.contest('estimate', 0, clock=False)
    assert list(j.due()) == []  # its state is still waited for
    j.offer('position', 0, 1e-3)
    ((ns, inputs),) = list(j.due())
    assert ns == 0 and is_contested(inputs)
    assert inputs == {'estimate': CONTESTED, 'position': 1e-3}


def test_a_contested_state_stands_in_for_every_input_of_its_sample() -> None:
    j = join()
    j.offer('position', 0, 0.0)
    j.offer('estimate', 0, Estimate(0.0, 0.0, 0.0))
    ((_, first),) = list(j.due())
    assert not is_contested(first)
    j.contest('position', T, clock=True)
    ((ns, inputs),) = list(j.due())  # no estimate of it waited for
    assert ns == T and inputs == {'position': CONTESTED, 'estimate': CONTESTED}
    j.offer('estimate', T, Estimate(0.0, 0.0, 0.0))  # late: the sample is answered
    assert list(j.due()) == [] and j.waiting_for() is None


def test_a_contested_state_estimate_or_model_is_answered_by_a_brake_a_reference_is_not() -> None:
    for slot in (CLOCK_INPUT, 'estimate', 'model'):
        assert brakes_on_contest(slot, CONTESTED_SENDER)
        assert not brakes_on_contest(slot, FOREIGN)  # a foreign sender: only refused
    assert not brakes_on_contest('reference', CONTESTED_SENDER)
