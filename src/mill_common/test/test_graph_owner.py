"""The sender of a message as the ROS graph identifies it (issue 37 items 1–2, issue 34
item 3): real rclpy nodes in a private domain; the publisher GID each message arrives with,
matched against the graph's endpoints of the owner node."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import pytest
from mill_common.checks import CONTESTED, FOREIGN, OWNER, Sender, sender_check
from mill_common.in_process import Graph

TOPIC = 'mill/x/joint_command'


@pytest.fixture
def graph() -> Iterator[Graph]:
    with Graph(190) as graph:
        yield graph


def receiver(graph: Any, contests: list[tuple[str, str, tuple[str, ...]]]) -> tuple[Any, list]:
    """A node taking TOPIC, owned by x_controller: [(frame_id, Sender)] of what it got."""
    from mill_common.codec import decode_joint_state
    from mill_common.ros import DATA_QOS, graph_owners, take_owned
    from sensor_msgs.msg import JointState

    node = graph.node('plant')
    owners = graph_owners(node, lambda *told: contests.append(told))
    got: list[tuple[str, Sender]] = []
    take_owned(
        node,
        JointState,
        TOPIC,
        decode_joint_state,
        lambda msg, who: got.append((msg.header.frame_id, who)),
        DATA_QOS,
        lambda problem: pytest.fail(problem.reason),
        owners,
        'x_controller',
    )
    node.owners = owners
    return node, got


def sender(graph: Any, name: str) -> Callable[[str], None]:
    """A node `name` whose publish(frame_id) sends one command on TOPIC."""
    from mill_common.ros import DATA_QOS, joint_state_bytes
    from sensor_msgs.msg import JointState

    pub = graph.node(name).create_publisher(JointState, TOPIC, DATA_QOS)
    return lambda frame_id: pub.publish(
        joint_state_bytes(0, ('x',), effort=(1.0,), sender=frame_id)
    )


def test_a_publisher_writing_the_owners_name_in_frame_id_is_told_apart_by_its_gid(graph) -> None:
    _node, got = receiver(graph, [])
    real, rogue = sender(graph, 'x_controller'), sender(graph, 'rogue')

    def both_heard() -> bool:
        real('x_controller')
        rogue('x_controller')  # what the attack of issue 37 wrote
        return {w.verdict for _, w in got} >= {OWNER, FOREIGN}

    assert graph.spin_until(both_heard)
    claims = {f for f, _ in got}
    assert claims == {'x_controller'}  # the frame_id cannot tell them apart
    verdicts = {w.name: w.verdict for _, w in got}
    assert verdicts == {'/x_controller': OWNER, '/rogue': FOREIGN}
    rogue_verdict = next(w for _, w in got if w.name == '/rogue')
    problem = sender_check(rogue_verdict, 'x_controller')
    assert problem is not None
    assert problem.reason == "sent by /rogue, not by its owner 'x_controller'"


def test_two_nodes_with_the_owners_name_are_both_refused_and_named_once(graph) -> None:
    contests: list[tuple[str, str, tuple[str, ...]]] = []
    node, got = receiver(graph, contests)
    first = sender(graph, 'x_controller')
    assert graph.spin_until(
        lambda: first('x_controller') or any(w.verdict == OWNER for _, w in got)
    )
    second = sender(graph, 'x_controller')  # a second process started with the same name

    def both_refused() -> bool:
        first('x_controller')
        second('x_controller')
        graph.spin(0.1)  # both delivered
        return len(got) >= 2 and all(w.verdict == CONTESTED for _, w in got[-2:])

    assert graph.spin_until(both_refused)
    gids = sorted(bytes(i.endpoint_gid).hex() for i in node.get_publishers_info_by_topic(TOPIC))
    assert len(gids) == 2 and gids[0] != gids[1]
    (topic, owner, claimants), *more = contests
    assert not more  # told once, however many messages follow
    assert (topic, owner) == (TOPIC, 'x_controller')
    assert len(claimants) == 2 and all(c.startswith('/x_controller (gid ') for c in claimants)
    named = sorted(c.split('(gid ')[1].rstrip(')').replace('.', '') for c in claimants)
    assert named == gids  # both named, each by its endpoint's GID
    assert {w.name for _, w in got[-2:]} == {'/x_controller'}
    problem = sender_check(got[-1][1], 'x_controller')
    assert problem is not None and problem.reason.startswith(
        "2 publishers claim to be 'x_controller': /x_controller (gid "
    )


def test_a_node_started_again_in_place_of_a_silent_one_is_the_owner_until_both_speak(
    graph,
) -> None:
    # A killed node's endpoint stays in the graph until its lease runs out: here the first
    # node stops speaking (as a killed one would) and a second of the same name takes over.
    from mill_common.graph_owner import LIVE_S

    contests: list[tuple[str, str, tuple[str, ...]]] = []
    _node, got = receiver(graph, contests)
    first = sender(graph, 'x_controller')
    assert graph.spin_until(lambda: first('x_controller') or bool(got))
    graph.spin(2 * LIVE_S)  # silent since
    again = sender(graph, 'x_controller')
    heard = len(got)
    assert graph.spin_until(lambda: again('x_controller') or len(got) >= heard + 5)
    assert [w.verdict for _, w in got[heard:]] == [OWNER] * (len(got) - heard)
    assert contests == []
    first('x_controller')  # it was alive after all: from now on both are refused

    def both_refused() -> bool:
        again('x_controller')
        return got[-1][1].verdict == CONTESTED

    assert graph.spin_until(both_refused)
    assert len(contests) == 1 and len(contests[0][2]) == 2


def test_a_message_larger_than_the_first_buffer_arrives_whole_with_its_gid(graph) -> None:
    from mill_common.codec import decode_joint_state
    from mill_common.graph_owner import GidSubscription
    from mill_common.ros import DATA_QOS, joint_state_bytes
    from sensor_msgs.msg import JointState

    node = graph.node('reader')
    got: list[tuple[bytes, bytes]] = []
    GidSubscription(node, JointState, 'big', lambda data, gid: got.append((data, gid)), DATA_QOS)
    names = tuple(f'joint_{i}' for i in range(600))  # ~ 16 kB: more than the 4 kB buffer
    sent = joint_state_bytes(7, names, position=[float(i) for i in range(600)], sender='w')
    pub = graph.node('writer').create_publisher(JointState, 'big', DATA_QOS)
    assert graph.spin_until(lambda: pub.publish(sent) or bool(got))
    data, gid = got[0]
    assert data == sent and len(sent) > 4096
    msg = decode_joint_state(data)
    assert list(msg.position)[-1] == 599.0
    (info,) = node.get_publishers_info_by_topic('big')
    assert gid == bytes(info.endpoint_gid)


def test_a_gid_the_graph_does_not_show_is_unknown_and_refused_once_the_owner_is_known(
    graph,
) -> None:
    from mill_common.checks import UNKNOWN

    node, got = receiver(graph, [])
    resolved = node.resolve_topic_name(TOPIC)
    stranger = bytes(range(16))  # no endpoint of this graph
    before = node.owners.verdict(resolved, stranger)
    assert before.verdict == UNKNOWN and before.claimants == ()
    assert sender_check(before, 'x_controller') is None  # its frame_id decides, at a start
    owner = sender(graph, 'x_controller')
    assert graph.spin_until(
        lambda: owner('x_controller') or any(w.verdict == OWNER for _, w in got)
    )
    after = node.owners.verdict(resolved, stranger)
    assert after.verdict == UNKNOWN and len(after.claimants) == 1
    assert after.claimants[0].startswith('/x_controller (gid ')
    problem = sender_check(after, 'x_controller')
    assert problem is not None and problem.reason.endswith(': refused until named')
