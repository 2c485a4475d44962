"""The recorder resolves topic names as its node does: namespace and remappings, as
`ros2 bag record` does; the bag holds absolute names."""

from __future__ import annotations

from pathlib import Path

import pytest
from mill_bag.errors import BagError
from mill_bag.recorder import TopicRecorder


def test_relative_names_resolve_under_the_namespace(node_in, tmp_path: Path) -> None:
    node = node_in('robot2', '/clock:=/robot2/clock')
    rec = TopicRecorder(node, tmp_path / 'bag', topics=['arm/state', '/joint_states'])
    assert rec.names == {'/robot2/arm/state', '/joint_states'}
    assert rec.resolve('/clock') == '/robot2/clock'  # remapped as the node's own
    rec.tap('arm/state', 'sensor_msgs/msg/JointState')
    with pytest.raises(BagError, match='recorded twice'):  # same topic, absolute name
        rec.tap('/robot2/arm/state', 'sensor_msgs/msg/JointState')
    rec.close()


def test_an_invalid_name_is_one_line(node_in, tmp_path: Path) -> None:
    with pytest.raises(BagError, match="topic name 'arm state' is not valid"):
        TopicRecorder(node_in('robot2'), tmp_path / 'bag', topics=['arm state'])
