"""The recorder's side of the lockstep handshake (mill_bringup.recorded_steps)."""

from __future__ import annotations

import pytest
from mill_bringup.recorded_steps import RecordedSteps

T = 1_000_000  # 1 ms
STATE, COMMAND, TRUTH = 'mill/x/state', 'mill/x/joint_command', 'mill/ground_truth'


def steps(window: int = 8) -> RecordedSteps:
    return RecordedSteps({STATE: 0, COMMAND: 0, TRUTH: 1}, T, window)


def plant_may_publish(acked: int, window: int, j: int) -> bool:
    """The plant's rule (mill_plant.drive_cycle.LockstepCycle): j T <= acknowledged + W T."""
    return j * T <= acked + window * T


def test_a_step_is_whole_when_every_heard_topic_has_it():
    s = steps()
    for k in range(5):
        s.heard(STATE, k * T)
    assert s.through == 4 * T  # only the states heard so far
    s.heard(COMMAND, 2 * T)
    assert s.through == 2 * T
    s.heard(TRUTH, 3 * T)  # the ground truth of step 3 comes with the states of step 4
    assert s.through == 2 * T
    s.heard(COMMAND, 4 * T)
    assert s.through == 4 * T


def test_nothing_counts_before_the_first_topic_and_other_topics_are_ignored():
    s = steps()
    assert s.heard(COMMAND, 7 * T) is None and s.through == -1
    assert s.heard('/rosout', 9 * T) is None and not s.stepped('/rosout')


def test_acknowledged_every_quarter_window_and_never_backwards():
    s = steps(window=8)
    acks = []
    for k in range(20):
        for topic in (STATE, COMMAND):
            ack = s.heard(topic, k * T)
            if ack is not None:
                acks.append(ack // T)
    assert acks == [2, 4, 6, 8, 10, 12, 14, 16, 18]  # stride 8 // 4 = 2 steps
    assert s.heard(STATE, 3 * T) is None  # a re-offered old step changes nothing


def test_freeze_lets_the_plant_pass_the_last_sample_once_and_waits_for_it():
    window = 8
    s = steps(window)
    for k in range(3):
        for topic in (STATE, COMMAND):
            s.heard(topic, k * T)
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
        for topic in (STATE, COMMAND):
            s.heard(topic, k * T)
    assert s.sent == 38 * T
    assert s.freeze(30) is None and s.frozen_at == 46 * T  # where it may go already
    assert not s.drained


def test_a_window_below_one_step_is_refused():
    with pytest.raises(ValueError):
        RecordedSteps({STATE: 0}, T, 0)
