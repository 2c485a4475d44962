"""The recorder's side of the lockstep handshake (mill_bringup.bag_handshake)."""

from __future__ import annotations

import pytest
from mill_bringup.bag_handshake import RecordedSteps
from mill_common.lockstep import RecorderGate
from mill_common.timebase import sample_stamp_ns

T = 1_000_000  # 1 ms [ns]
STATE, COMMAND, TRUTH = 'mill/x/state', 'mill/x/joint_command', 'mill/ground_truth'


def steps(window: int = 8) -> RecordedSteps:
    return RecordedSteps({STATE: 0, COMMAND: 0, TRUTH: 1}, T / 1e9, window)


def step_messages(k: int, command: bool = True) -> list[tuple[str, int]]:
    """What the plant, a controller and the plant again send with step k: its state, its
    command, and with the state the ground truth of step k - 1."""
    out = [(STATE, k * T)] + ([(TRUTH, (k - 1) * T)] if k else [])
    return out + ([(COMMAND, k * T)] if command else [])


def run(
    s: RecordedSteps, window: int, steps_per_write: int, last: int = 99, command: bool = True
) -> tuple[int, list[int]]:
    """The plant steps as the acknowledgements let it (mill_common.lockstep.RecorderGate)
    until step `last`; the recorder writes its bag every `steps_per_write` steps it takes in
    and acknowledges after each write. The step the plant stopped at, and the acks [steps]."""
    gate = RecorderGate(window, T / 1e9)
    if s.sent >= 0:
        gate.acknowledged(s.sent)
    acks: list[int] = []
    k = 0
    while k <= last and gate.allows(k):
        for topic, ns in step_messages(k, command):
            s.heard(topic, ns)
        if (k + 1) % steps_per_write == 0 and (ack := s.written()) is not None:
            acks.append(ack // T)
            gate.acknowledged(ack)
        k += 1
    return k, acks


def test_a_step_is_whole_when_every_topic_has_it() -> None:
    s = steps()
    for k in range(5):
        s.heard(STATE, k * T)
    assert s.through == -1 and s.written() is None  # no command and no ground truth yet
    s.heard(COMMAND, 2 * T)
    assert s.through == -1 and s.behind() == [TRUTH]
    s.heard(TRUTH, 3 * T)  # the ground truth of step 3 comes with the states of step 4
    assert s.through == 2 * T and s.behind() == [COMMAND]
    s.heard(COMMAND, 4 * T)
    assert s.through == 4 * T
    assert s.written() == 4 * T and s.written() is None  # acknowledged once


def test_commands_never_heard_hold_the_plant_at_the_window() -> None:
    """The load that lost commands 0-648 of two axes: the runner had not matched their
    senders. A topic not yet heard holds the plant W steps in, it does not let it run on."""
    s = steps(window=8)
    stopped, acks = run(s, 8, steps_per_write=1, command=False)
    assert stopped == 8 and acks == [] and s.behind() == [COMMAND]


def test_a_runner_without_a_bag_waits_only_for_the_topics_it_keeps() -> None:
    """Unrecorded, the runner keeps no ground truth (say): the handshake over what it keeps
    lets the plant run to the end; over every stepped topic it would hold it at the window."""
    s = steps(window=8).only([STATE, COMMAND, 'mill/x/estimate'])
    assert s.stepped(STATE) and s.stepped(COMMAND) and not s.stepped(TRUTH)
    stopped, acks = run(s, 8, steps_per_write=1)
    assert stopped == 100 and acks[-1] == 99


def test_only_what_was_written_is_acknowledged_so_the_plant_stays_a_window_ahead_of_the_file():
    s = steps(window=8)
    stopped, acks = run(s, 8, steps_per_write=3, last=40)
    assert acks[:4] == [2, 5, 8, 11]  # after each write, the newest step it holds whole
    assert stopped == 41  # ... and the plant went on to the end
    # A SIGKILL of the recorder between two writes: the file holds every step up to the last
    # acknowledgement, the plant sent at most `window` steps more.
    s = steps(window=8)
    stopped, acks = run(s, 8, steps_per_write=20, last=40)
    assert stopped == 8 and acks == []  # no write yet: held at the window
    assert s.heard('/rosout', 9 * T) is None and not s.stepped('/rosout')


def test_freeze_lets_the_plant_pass_the_last_sample_once_and_waits_for_it():
    window = 8
    s = steps(window)
    for k in range(3):
        for topic, ns in step_messages(k):
            s.heard(topic, ns)
    assert s.written() == 2 * T and s.sent == 2 * T
    # the job has 30 samples: the plant may go on to step 30 (ground truth of 29)
    assert s.freeze(30) is None and s.frozen_at == 30 * T and not s.drained
    stopped, acks = run(s, window, steps_per_write=1, last=39)
    assert stopped == 31  # it stopped right after the step that carries the last ground truth
    assert acks[-1] == 30 - window and s.drained


def test_freeze_when_the_plant_is_already_past_the_end():
    s = steps(window=8)
    for k in range(40):
        for topic, ns in step_messages(k):
            s.heard(topic, ns)
    assert s.written() == 39 * T
    assert s.freeze(30) is None and s.frozen_at == 47 * T  # where it may go already
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
            s.heard(topic, ns)
        if k % 2 and (ack := s.written()) is not None:  # a write every second revolution
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
