"""benchmark --realtime: the latency per hop from one listener's arrival times."""

from __future__ import annotations

import math

import pytest
from mill_bench.hops import hop_latencies, quantiles_ms, timed_messages, timed_topics
from mill_common.codec import encode_joint_state

from mill_common import topics

MS = 1_000_000  # [ns]
T0 = 1_700_000_000 * 1_000_000_000  # a wall-clock stamp


def loop(stamps: list[int], state: int, estimate: int, command: int) -> dict:
    """x's messages of these states, arriving `state`, `estimate`, `command` ns after each."""
    return {
        topics.state('x'): [(s, s + state) for s in stamps],
        topics.estimate('x'): [(s, s + estimate) for s in stamps],
        topics.joint_command('x'): [(s, s + command) for s in stamps],
    }


def test_each_hop_is_the_difference_of_two_arrivals_and_the_state_its_stamp() -> None:
    stamps = [T0 + k * 2 * MS for k in range(10)]
    got = hop_latencies(loop(stamps, MS // 5, MS // 2, 3 * MS // 4), ['x'])['x']
    assert got['state'] == pytest.approx((0.2, 0.2))
    assert got['observer'] == pytest.approx((0.3, 0.3))
    assert got['controller'] == pytest.approx((0.25, 0.25))
    assert got['loop'] == pytest.approx((0.55, 0.55))


def test_only_states_both_messages_answer_count_and_the_first_arrival() -> None:
    stamps = [T0 + k * MS for k in range(4)]
    timed = loop(stamps, 0, MS, 2 * MS)
    timed[topics.joint_command('x')] = [(stamps[0], stamps[0] + 2 * MS)]  # three unanswered
    timed[topics.joint_command('x')].append((stamps[0], stamps[0] + 50 * MS))  # again, later
    got = hop_latencies(timed, ['x'])['x']
    assert got['loop'] == pytest.approx((2.0, 2.0))
    assert got['observer'] == pytest.approx((1.0, 1.0))


def test_the_window_leaves_out_states_outside_the_job() -> None:
    stamps = [T0 + k * MS for k in range(10)]
    timed = loop(stamps, 0, 0, MS)
    late = T0 + 9 * MS  # the last command came 40 ms late: after the job
    timed[topics.joint_command('x')][-1] = (late, late + 40 * MS)
    assert hop_latencies(timed, ['x'])['x']['loop'][1] > 1.0
    windowed = hop_latencies(timed, ['x'], (stamps[0], stamps[8]))['x']
    assert windowed['loop'] == pytest.approx((1.0, 1.0))


def test_the_floor_has_no_observer_hop() -> None:
    stamps = [T0 + k * MS for k in range(5)]
    timed = loop(stamps, MS // 10, 0, MS // 2)
    del timed[topics.estimate('x')]
    got = hop_latencies(timed, ['x', 'y'])
    assert set(got['x']) == {'state', 'loop'}
    assert got['y'] == {}  # nothing heard of y


def test_median_and_p99_as_numpy_and_nan_for_none() -> None:
    median, p99 = quantiles_ms([k * MS for k in range(1, 101)])
    assert median == pytest.approx(50.5)
    assert p99 == pytest.approx(99.01)
    assert all(math.isnan(v) for v in quantiles_ms([]))


class Listener:
    """What hops read of the runner's monitor."""

    def __init__(self, messages: dict[str, list[bytes]], arrivals: dict[str, list[int]]) -> None:
        self._messages, self._arrivals = messages, arrivals

    def messages(self, topic: str) -> list[bytes]:
        return self._messages.get(topic, [])

    def arrival_ns(self, topic: str) -> list[int]:
        return self._arrivals.get(topic, [])


def test_stamps_are_read_from_the_messages_the_listener_took() -> None:
    state = topics.state('x')
    data = [encode_joint_state(T0 + k * MS, 'plant', ('x',), (0.0,)) for k in range(3)]
    listener = Listener({state: [*data, b'\x00']}, {state: [T0 + 7, T0 + MS + 8, T0 + 2 * MS + 9]})
    got = timed_messages(listener, [state, topics.estimate('x')])
    assert got[state] == [(T0, T0 + 7), (T0 + MS, T0 + MS + 8), (T0 + 2 * MS, T0 + 2 * MS + 9)]
    assert got[topics.estimate('x')] == []


def test_the_listener_times_state_estimate_and_command_of_every_axis() -> None:
    assert timed_topics(['x', 'z']) == {
        f'mill/{a}/{t}' for a in 'xz' for t in ('state', 'estimate', 'joint_command')
    }
