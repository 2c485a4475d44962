"""The recorder's side of the lockstep handshake (mill_bringup.recorded_steps)."""

from __future__ import annotations

import pytest
from mill_bringup.recorded_steps import RecordedSteps
from mill_common.lockstep import RecorderGate
from mill_common.timebase import sample_stamp_ns

T = 1_000_000  # 1 ms [ns]
STATE, COMMAND, TRUTH = 'mill/x/state', 'mill/x/joint_command', 'mill/ground_truth'


def steps(window: int = 8) -> RecordedSteps:
    return RecordedSteps({STATE: 0, COMMAND: 0, TRUTH: 1}, T / 1e9, window)


def plant_may_publish(acked: int, window: int, j: int) -> bool:
    """The clock node's rule (mill_common.lockstep.RecorderGate)."""
    gate = RecorderGate(window, T / 1e9)
    if acked >= 0:
        gate.acknowledged(acked)
    return gate.allows(j)


def test_a_step_is_whole_when_every_topic_has_it() -> None:
    s = steps()
    for k in range(5):
        s.heard(STATE, k * T)
    assert s.through == -1  # no command and no ground truth yet
    s.heard(COMMAND, 2 * T)
    assert s.through == -1 and s.behind() == [TRUTH]
    s.heard(TRUTH, 3 * T)  # the ground truth of step 3 comes with the states of step 4
    assert s.through == 2 * T and s.behind() == [COMMAND]
    s.heard(COMMAND, 4 * T)
    assert s.through == 4 * T


def test_commands_never_heard_hold_the_plant_at_the_window() -> None:
    """The load that lost commands 0-648 of two axes: the runner had not matched their
    senders. A topic not yet heard holds the plant W steps in, it does not let it run on."""
    window = 8
    s = steps(window)
    gate_at = -1
    for k in range(100):
        if not plant_may_publish(gate_at * T if gate_at >= 0 else -1, window, k):
            break
        for topic, ns in ((STATE, k * T), (TRUTH, (k - 1) * T)):  # no command is heard
            if ns >= 0 and (ack := s.heard(topic, ns)) is not None:
                gate_at = ack // T
    assert k == window and gate_at == -1 and s.behind() == [COMMAND]


def test_other_topics_are_ignored() -> None:
    s = steps()
    assert s.heard('/rosout', 9 * T) is None and not s.stepped('/rosout')


def test_acknowledged_every_quarter_window_and_never_backwards():
    s = steps(window=8)
    acks = []
    for k in range(20):
        for topic, ns in ((STATE, k * T), (COMMAND, k * T), (TRUTH, (k - 1) * T)):
            ack = s.heard(topic, ns) if ns >= 0 else None
            if ack is not None:
                acks.append(ack // T)
    assert acks == [2, 4, 6, 8, 10, 12, 14, 16, 18]  # stride 8 // 4 = 2 steps
    assert s.heard(STATE, 3 * T) is None  # a re-offered old step changes nothing


def test_freeze_lets_the_plant_pass_the_last_sample_once_and_waits_for_it():
    window = 8
    s = steps(window)
    for k in range(3):
        for topic, ns in ((STATE, k * T), (COMMAND, k * T), (TRUTH, (k - 1) * T)):
            if ns >= 0:
                s.heard(topic, ns)
    assert s.sent == 2 * T
    # the job has 30 samples: the plant may go on to step 30 (ground truth of 29)
    ack = s.freeze(30)
    assert ack is None and s.frozen_at == 30 * T and not s.drained
    acks = []
    for k in range(3, 40):  # what the plant publishes, as the acknowledgements let it
        if not plant_may_publish(s.sent, window, k):
            break
        for topic in (STATE, COMMAND, TRUTH):
            ack = s.heard(topic, (k - 1 if topic == TRUTH else k) * T)
            if ack is not None:
                acks.append(ack // T)
    assert k == 31  # it stopped right after the step that carries the last ground truth
    assert acks[-1] == 30 - window and s.drained


def test_freeze_when_the_plant_is_already_past_the_end():
    s = steps(window=8)
    for k in range(40):
        for topic, ns in ((STATE, k * T), (COMMAND, k * T), (TRUTH, (k - 1) * T)):
            if ns >= 0:
                s.heard(topic, ns)
    assert s.sent == 38 * T
    assert s.freeze(30) is None and s.frozen_at == 46 * T  # where it may go already
    assert not s.drained


def test_a_window_below_one_step_is_refused():
    with pytest.raises(ValueError):
        RecordedSteps({STATE: 0}, T / 1e9, 0)


def test_a_period_of_no_whole_ns_acknowledges_the_clock_nodes_own_stamps() -> None:
    # One spindle revolution at 7000 rpm (Rubio's force job): stamps are the nearest ns.
    period = 60.0 / 7000.0
    stamps = [sample_stamp_ns(k, period) for k in range(100)]
    force, trace = 'mill/cutting_force', 'mill/cutting_force/trace'
    s = RecordedSteps({force: 0, trace: 1}, period, 8)
    gate = RecorderGate(8, period)
    acks = []
    for k in range(100):
        if not gate.allows(k):
            break
        heard = [(force, stamps[k])] + ([(trace, stamps[k - 1])] if k else [])
        for topic, ns in heard:  # what the clock node publishes with sample k
            ack = s.heard(topic, ns)
            if ack is not None:
                acks.append(ack)
                gate.acknowledged(ack)
    assert k == 99  # the acknowledgements kept the clock node going to the end
    assert acks and set(acks) <= set(stamps)  # its own stamps, whole ns or not
    assert s.through == stamps[99]  # whole: its force, and the trace of 98 that came with it
    assert acks[-1] == stamps[gate.recorded]


def test_the_gate_without_a_window_never_holds() -> None:
    gate = RecorderGate(0, 1e-3)
    assert gate.allows(10**9) and gate.describe() == 'none'
    gate = RecorderGate(4, 1e-3)
    assert gate.allows(3) and not gate.allows(4)  # W samples from the start
    gate.acknowledged(3_000_000)
    assert gate.allows(7) and not gate.allows(8) and gate.describe() == 't = 0.003 s'
