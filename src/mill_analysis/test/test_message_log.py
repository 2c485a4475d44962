"""MessageLog: the runner's compact store of a topic's serialized messages."""

from __future__ import annotations

import struct

import pytest
from mill_analysis.node_intake import (
    ArrivalOrder,
    Forgotten,
    MessageLog,
    Received,
    arrival_order,
    subset,
)


def _message(k: int) -> bytes:
    """A CDR-like sample: a header with the stamp, a frame id, three doubles."""
    return (
        struct.pack('<4xiI', k // 1000, (k % 1000) * 1_000_000)
        + b'x_axis\0\0'
        + struct.pack('<3d', 0.001 * k, -2.5 * k, 1.0 / (k + 1))
        + bytes(k % 7)
    )


def test_every_message_comes_back_as_it_was_appended_across_chunks() -> None:
    sent = [_message(k) for k in range(20_000)]
    log = MessageLog()
    for data in sent:
        log.append(data)
    assert len(log) == len(sent)
    assert log.nbytes() < 0.7 * sum(len(d) for d in sent)  # compressed, not a copy
    assert list(log) == sent
    assert log[-1] == sent[-1] and log[0] == sent[0]
    assert log[12_345] == sent[12_345]  # random access back into an older chunk
    assert log[-3:] == sent[-3:]
    with pytest.raises(IndexError):
        log[len(sent)]


def test_an_empty_log_is_false_and_holds_nothing() -> None:
    log = MessageLog()
    assert not log and len(log) == 0 and list(log) == []
    log.append(b'')
    assert log and log[0] == b''


def test_the_order_of_arrival_reads_through_logs() -> None:
    raw = Received()
    raw['a'] = MessageLog([b'a0', b'a1'])
    raw['b'] = MessageLog([b'b0'])
    raw.order = ArrivalOrder(['a', 'b', 'a'])
    assert list(arrival_order(raw, ['a', 'b'])) == [('a', b'a0'), ('b', b'b0'), ('a', b'a1')]
    only = subset(raw, ['a'])
    assert only['a'] is raw['a'] and list(only.order) == ['a', 'a']


def test_the_arrival_order_gives_back_the_names_in_order() -> None:
    names = ['mill/x/state', 'mill/x/estimate', 'mill/x/state', '/clock'] * 1000
    order = ArrivalOrder()
    for name in names:
        order.append(name)
    assert len(order) == 4000 and list(order) == names
    assert order[2] == 'mill/x/state' and order[-1] == '/clock' and order[1:3] == names[1:3]


def test_the_missing_runs_of_flags_are_those_of_the_sample_set() -> None:
    import numpy as np
    from mill_analysis.bag_meta import missing_ranges
    from mill_analysis.lockstep_record import missing_runs

    rng = np.random.default_rng(7)
    for n in (0, 1, 5, 200):
        for share in (0.0, 0.3, 0.9, 1.0):
            have = rng.random(n) < share
            want = missing_ranges(set(np.flatnonzero(have).tolist()), n)
            assert missing_runs(have) == want


def test_a_forgotten_log_counts_every_message_and_holds_the_newest() -> None:
    sent = [_message(k) for k in range(20_000)]
    log = MessageLog(sent)
    full = log.nbytes()
    log.forget()
    assert len(log) == 20_000 and log[-1] == sent[-1] and log[19_999] == sent[-1]
    assert log.nbytes() < 100 < full  # the newest message and its index
    with pytest.raises(Forgotten, match='message 12345 of 20000 was forgotten'):
        log[12_345]
    for k in range(20_000, 30_000):  # what comes after is kept again, across chunks
        log.append(_message(k))
    assert len(log) == 30_000 and log[-1] == _message(29_999) and log[25_000] == _message(25_000)
    assert log[19_999] == sent[-1]
    with pytest.raises(IndexError):
        log[30_000]


def test_received_forgets_all_but_the_topics_kept() -> None:
    raw = Received()
    raw['a'] = MessageLog([b'a0', b'a1'])
    raw['b'] = MessageLog([b'b0', b'b1', b'b2'])
    raw.order = ArrivalOrder(['a', 'b', 'b', 'a', 'b'])
    raw.forget(keep={'b'})
    assert list(raw['b']) == [b'b0', b'b1', b'b2'] and len(raw.order) == 5
    assert len(raw['a']) == 2 and raw['a'][-1] == b'a1'
    with pytest.raises(Forgotten):
        raw['a'][0]
    raw.forget()
    assert len(raw['b']) == 3 and raw['b'][-1] == b'b2' and len(raw.order) == 0


def test_messages_of_64_kb_and_more_keep_their_lengths() -> None:
    sent = [bytes([k % 251]) * (k * 7919 % 150_000) for k in range(60)]
    log = MessageLog(sent[:30])  # two bytes a length until one is 64 kB or more
    for data in sent[30:]:
        log.append(data)
    assert list(log) == sent and log[3] == sent[3] and log[-1] == sent[-1]
