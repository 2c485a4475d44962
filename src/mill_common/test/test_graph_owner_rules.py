"""The rules of mill_common.graph_owner on a graph and a clock the test sets: who is the
owner while a killed node's endpoint lingers, and what a publisher the graph does not name
yet may do while the graph shows the owner. (test_graph_owner.py runs them against real DDS.)"""

from __future__ import annotations

from dataclasses import dataclass, field

import pytest
from mill_common.checks import CONTESTED, FOREIGN, OWNER, UNKNOWN, sender_check
from mill_common.graph_owner import LIVE_S, GraphOwners

from mill_common import graph_owner

TOPIC = '/mill/x/joint_command'
A, B, R = bytes([1] * 16), bytes([2] * 16), bytes([3] * 16)


@dataclass
class Info:
    endpoint_gid: bytes
    node_name: str
    node_namespace: str = '/'


@dataclass
class FakeNode:
    """What GraphOwners asks of a node: the graph's publishers of a topic."""

    publishers: list[Info] = field(default_factory=list)

    def get_namespace(self) -> str:
        return '/'

    def resolve_topic_name(self, topic: str) -> str:
        return '/' + topic.lstrip('/')

    def count_publishers(self, topic: str) -> int:
        return len(self.publishers)

    def get_publishers_info_by_topic(self, topic: str) -> list[Info]:
        return list(self.publishers)


@pytest.fixture
def clock(monkeypatch: pytest.MonkeyPatch) -> list[float]:
    now = [100.0]
    monkeypatch.setattr(graph_owner.time, 'monotonic', lambda: now[0])
    return now


def owners(node: FakeNode, told: list[tuple[str, ...]]) -> GraphOwners:
    graph = GraphOwners(node, on_contested=lambda topic, owner, names: told.append(names))  # type: ignore[arg-type]
    graph.watch(TOPIC, 'x_controller')
    return graph


def test_the_node_started_in_place_of_a_silent_one_is_obeyed_until_the_old_one_speaks(
    clock: list[float],
) -> None:
    node, told = FakeNode([Info(A, 'x_controller')]), []
    graph = owners(node, told)
    assert graph.verdict(TOPIC, A).verdict == OWNER
    clock[0] += 1.5  # killed; a new process of the same name starts; the old endpoint lingers
    node.publishers.append(Info(B, 'x_controller'))
    graph.look()
    for _ in range(3):
        clock[0] += 0.002
        assert graph.verdict(TOPIC, B).verdict == OWNER
    assert told == []
    clock[0] += 0.002
    again = graph.verdict(TOPIC, A)  # it was only stopped: now two speak
    assert again.verdict == CONTESTED and len(again.claimants) == 2
    assert graph.verdict(TOPIC, B).verdict == CONTESTED
    assert len(told) == 1  # named once per set


def test_a_second_copy_started_beside_a_speaking_owner_is_refused_from_its_first_message(
    clock: list[float],
) -> None:
    node, told = FakeNode([Info(A, 'x_controller')]), []
    graph = owners(node, told)
    assert graph.verdict(TOPIC, A).verdict == OWNER
    node.publishers.append(Info(B, 'x_controller'))
    graph.look()
    clock[0] += LIVE_S / 2
    assert graph.verdict(TOPIC, B).verdict == CONTESTED
    clock[0] += 5.0  # a pause of the whole graph: still both speak once it goes on
    assert graph.verdict(TOPIC, A).verdict == CONTESTED
    assert graph.verdict(TOPIC, B).verdict == CONTESTED


def test_a_publisher_the_graph_does_not_name_yet_is_refused_while_it_shows_the_owner(
    clock: list[float],
) -> None:
    node = FakeNode()
    graph = owners(node, [])
    # The start: the graph shows no endpoint of the owner yet, the frame_id claim decides.
    first = graph.verdict(TOPIC, A)
    assert first.verdict == UNKNOWN and sender_check(first, 'x_controller') is None
    node.publishers.append(Info(A, 'x_controller'))
    clock[0] += 0.1
    assert graph.verdict(TOPIC, A).verdict == OWNER
    for _ in range(100):  # discovery slow to name it (a loaded host): never obeyed
        clock[0] += 0.05
        assert graph.verdict(TOPIC, A).verdict == OWNER
        unnamed = graph.verdict(TOPIC, R)
        assert unnamed.verdict == UNKNOWN and sender_check(unnamed, 'x_controller') is not None
    node.publishers.append(Info(R, 'rogue'))
    clock[0] += 0.1
    rogue = graph.verdict(TOPIC, R)
    assert (rogue.verdict, rogue.name) == (FOREIGN, '/rogue')


def test_the_owner_started_again_is_obeyed_once_the_graph_names_it(clock: list[float]) -> None:
    node = FakeNode([Info(A, 'x_controller')])
    graph = owners(node, [])
    assert graph.verdict(TOPIC, A).verdict == OWNER
    clock[0] += 1.5  # killed, and its successor speaks before discovery names it
    unnamed = graph.verdict(TOPIC, B)
    assert unnamed.verdict == UNKNOWN and sender_check(unnamed, 'x_controller') is not None
    node.publishers.append(Info(B, 'x_controller'))
    clock[0] += 0.1
    assert graph.verdict(TOPIC, B).verdict == OWNER
