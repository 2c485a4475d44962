"""In-process delivery between the nodes of one process (mill_common.intra_process)."""

from __future__ import annotations

import os
import time
from collections.abc import Iterator

import pytest
from mill_common.codec import decode_joint_state
from mill_common.intra_process import IntraProcess
from mill_common.ros import DATA_QOS, joint_state, joint_state_bytes

TOPIC = 'mill/x/state'


@pytest.fixture
def make_node(monkeypatch: pytest.MonkeyPatch) -> Iterator:
    import rclpy
    from rclpy.node import Node

    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(150 + os.getpid() % 50))
    context = rclpy.Context()
    rclpy.init(context=context)
    nodes: list[Node] = []

    def make(name: str) -> Node:
        nodes.append(Node(name, context=context))
        return nodes[-1]

    yield make
    for n in nodes:
        n.destroy_node()
    rclpy.try_shutdown(context=context)


def enabled() -> IntraProcess:
    bus = IntraProcess()
    bus.enabled = True
    return bus


def test_a_reader_of_a_local_publisher_gets_its_bytes_and_leaves_dds(make_node) -> None:
    from sensor_msgs.msg import JointState

    bus = enabled()
    plant, observer = make_node('plant'), make_node('observer')
    got: list[bytes] = []
    reader = bus.subscribe(observer, JointState, TOPIC, got.append, DATA_QOS)
    assert len(list(observer.subscriptions)) == 1  # nobody here publishes it yet: DDS
    out = bus.publisher(plant, JointState, TOPIC, DATA_QOS)
    assert not list(observer.subscriptions)  # now the plant in this process does
    data = joint_state_bytes(5, ('x',), position=(0.25,), sender='plant')
    out.publish(data)
    out.publish(joint_state_bytes(6, ('x',), position=(0.5,), sender='plant'))
    assert not got  # delivered by the spin loop, never inside the publisher's callback
    bus.drain(1)
    assert got == [data] and got[0] is data
    assert bus.pending()
    bus.drain(10)
    assert [decode_joint_state(b).position for b in got] == [(0.25,), (0.5,)]
    assert not bus.pending()
    assert out.get_subscription_count() >= 1
    assert reader.get_publisher_count() >= 1
    assert out.topic_name == '/mill/x/state'


def test_a_reader_made_after_the_publisher_never_subscribes_over_dds(make_node) -> None:
    from sensor_msgs.msg import JointState

    bus = enabled()
    plant, a, b = make_node('plant'), make_node('a'), make_node('b')
    out = bus.publisher(plant, JointState, TOPIC, DATA_QOS)
    got_a: list[bytes] = []
    got_b: list[bytes] = []
    bus.subscribe(a, JointState, TOPIC, got_a.append, DATA_QOS)
    bus.subscribe(b, JointState, '/mill/x/state', got_b.append, DATA_QOS)
    assert not list(a.subscriptions) and not list(b.subscriptions)
    out.publish(joint_state(7, ('x',), position=(1.0,), sender='plant'))  # a message object
    bus.drain(10)
    from rclpy.serialization import serialize_message

    expected = serialize_message(joint_state(7, ('x',), position=(1.0,), sender='plant'))
    assert got_a == [expected] and got_b == [expected]


def test_other_topics_and_other_processes_still_go_over_dds(make_node) -> None:
    from sensor_msgs.msg import JointState

    bus = enabled()
    plant, observer = make_node('plant'), make_node('observer')
    bus.publisher(plant, JointState, 'mill/y/state', DATA_QOS)
    got: list[bytes] = []
    bus.subscribe(observer, JointState, TOPIC, got.append, DATA_QOS)
    assert len(list(observer.subscriptions)) == 1


def test_off_it_hands_out_plain_rclpy_publishers_and_subscriptions(make_node) -> None:
    from rclpy.publisher import Publisher
    from rclpy.subscription import Subscription
    from sensor_msgs.msg import JointState

    bus = IntraProcess()
    plant, observer = make_node('plant'), make_node('observer')
    assert isinstance(bus.publisher(plant, JointState, TOPIC, DATA_QOS), Publisher)
    assert isinstance(bus.subscribe(observer, JointState, TOPIC, print, DATA_QOS), Subscription)


def test_off_when_the_environment_says_so(monkeypatch: pytest.MonkeyPatch) -> None:
    bus = IntraProcess()
    monkeypatch.setenv('MILL_INTRA_PROCESS', '0')
    bus.enable()
    assert not bus.enabled
    monkeypatch.delenv('MILL_INTRA_PROCESS')
    bus.enable()
    assert bus.enabled


def test_a_publisher_outside_the_process_is_named(make_node) -> None:
    from sensor_msgs.msg import JointState

    bus = enabled()
    plant, observer, intruder = make_node('plant'), make_node('observer'), make_node('intruder')
    bus.publisher(plant, JointState, TOPIC, DATA_QOS)
    bus.subscribe(observer, JointState, TOPIC, print, DATA_QOS)
    bus._check_outsiders()
    assert bus._reported == {}  # the plant alone: nothing to say
    intruder.create_publisher(JointState, TOPIC, DATA_QOS)  # not through the bus
    deadline = time.monotonic() + 10.0
    while '/mill/x/state' not in bus._reported and time.monotonic() < deadline:
        bus._check_outsiders()
        time.sleep(0.05)
    assert '/intruder' in bus._reported['/mill/x/state']


def test_unsubscribed_it_gets_nothing_more_not_even_what_was_queued(make_node) -> None:
    from sensor_msgs.msg import JointState

    bus = enabled()
    plant, trajectory, observer = make_node('plant'), make_node('trajectory'), make_node('obs')
    out = bus.publisher(plant, JointState, TOPIC, DATA_QOS)
    gone: list[bytes] = []
    kept: list[bytes] = []
    handle = bus.subscribe(trajectory, JointState, TOPIC, gone.append, DATA_QOS)
    bus.subscribe(observer, JointState, TOPIC, kept.append, DATA_QOS)
    out.publish(b'first')
    bus.unsubscribe(trajectory, handle)
    out.publish(b'second')
    bus.drain(10)
    assert gone == [] and kept == [b'first', b'second']
    assert out.get_subscription_count() == 1 + out._publisher.get_subscription_count()


def test_off_unsubscribing_destroys_the_dds_subscription(make_node) -> None:
    from sensor_msgs.msg import JointState

    bus = IntraProcess()
    node = make_node('trajectory')
    handle = bus.subscribe(node, JointState, TOPIC, print, DATA_QOS)
    assert len(list(node.subscriptions)) == 1
    bus.unsubscribe(node, handle)
    assert not list(node.subscriptions)
