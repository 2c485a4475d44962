"""What a recorder lost: DDS's message_lost counts per topic, in metadata.yaml at every flush
and at close (custom_data messages_lost), read back by Bag.messages_lost."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import yaml
from mill_bag.reader import open_bag
from mill_bag.recorder import TopicRecorder
from mill_bag.writer import MESSAGES_LOST, BagWriter, counts_note

STATE = 'sensor_msgs/msg/JointState'


def lost(total: int) -> SimpleNamespace:
    # What rclpy hands the handler; under the EventsExecutor total_count_change came as 0.
    return SimpleNamespace(total_count=total, total_count_change=0)


def noted(bag: Path) -> dict:
    info = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    return info['custom_data']


def test_losses_are_counted_per_topic_and_noted_at_every_flush(node_in, tmp_path: Path) -> None:
    node = node_in('robot2')
    bag = tmp_path / 'bag'
    rec = TopicRecorder(node, bag, discover=False, custom_data={'kind': 'test'})
    assert noted(bag) == {'kind': 'test', MESSAGES_LOST: '{}'}  # counted, none lost
    rec.tap('arm/state', STATE)
    rec.tap('/clock', 'rosgraph_msgs/msg/Clock')
    on_arm = rec.lost_events('arm/state').message_lost
    on_clock = rec.lost_events('/clock').message_lost
    on_arm(lost(3))
    on_clock(lost(0))
    rec.flush()
    assert noted(bag)[MESSAGES_LOST] == '{"/robot2/arm/state": 3}'
    on_arm(lost(7))  # the subscription's running total
    on_arm(lost(5))  # an older report, handled late, takes nothing back
    rec.close()
    assert noted(bag) == {'kind': 'test', MESSAGES_LOST: '{"/robot2/arm/state": 7}'}
    assert open_bag(bag).messages_lost == {'/robot2/arm/state': 7}
    lines = rec.summary().splitlines()
    assert lines[1:] == ['WARNING: 7 messages lost on /robot2/arm/state (DDS message_lost)']


def test_a_recorder_that_lost_nothing_says_so_quietly(node_in, tmp_path: Path) -> None:
    rec = TopicRecorder(node_in('/'), tmp_path / 'bag', discover=False)
    rec.tap('/a', STATE)
    rec.close()
    assert open_bag(tmp_path / 'bag').messages_lost == {}
    assert len(rec.summary().splitlines()) == 1


def test_counts_notes_read_back_and_a_bag_without_one_has_none(tmp_path: Path) -> None:
    assert counts_note({'/b': 2, '/a': 0, '/c': 1}) == '{"/b": 2, "/c": 1}'
    notes = {'plain': 'x', 'counts': counts_note({'/b': 2}), 'broken': '[1, 2'}
    w = BagWriter(tmp_path / 'bag', custom_data=notes)
    w.close()
    bag = open_bag(tmp_path / 'bag')
    assert bag.noted_counts('counts') == {'/b': 2}
    assert bag.noted_counts('broken') is None and bag.noted_counts('plain') is None
    assert bag.noted_counts('absent') is None and bag.messages_lost is None  # another writer
