"""The RViz config and the Foxglove layout of the repository parse, and every topic they
name is one the graph has: the names are taken from mill_common.topics (every name it
declares, the per-axis ones for x, y, z), resolved in the default namespace, not listed by
hand. They also show what a viewer needs: the robot model and its frames, both paths, the
joint states and the diagnostics (those two in Foxglove: RViz has no display for them).
"""

from __future__ import annotations

import inspect
import json
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import yaml
from mill_common.signals import AXES

from mill_common import topics

CONFIG = Path(__file__).resolve().parents[1] / 'config'
RVIZ, FOXGLOVE = CONFIG / 'mill.rviz', CONFIG / 'mill.foxglove.json'
# An absolute ROS name, optionally followed by a Foxglove message path (`.position[0]`).
_NAME = re.compile(r'^(/[A-Za-z_][A-Za-z0-9_]*(?:/[A-Za-z_][A-Za-z0-9_]*)*)(?:\..*)?$')


def graph_topics() -> set[str]:
    """Every topic mill_common.topics names, as the default namespace resolves it."""
    names = set()
    for name, value in vars(topics).items():
        if name.isupper() and isinstance(value, str) and value not in ('', topics.ROOT):
            if re.fullmatch(r'/?[a-z_]+(/[a-z_]+)*', value):
                names.add(topics.qualify(value))
        elif inspect.isfunction(value) and list(inspect.signature(value).parameters) == ['axis']:
            names.update(topics.qualify(value(axis)) for axis in AXES)
    return names


def _strings(node: Any) -> Iterator[str]:
    if isinstance(node, str):
        yield node
    elif isinstance(node, dict):
        for key, value in node.items():
            yield from _strings(key)
            yield from _strings(value)
    elif isinstance(node, list):
        for value in node:
            yield from _strings(value)


def named_topics(document: Any) -> set[str]:
    """The ROS names a config refers to: every string that is one (a Foxglove message path
    counts by its topic)."""
    return {m.group(1) for s in _strings(document) if (m := _NAME.match(s))}


def test_the_graph_topics_come_from_the_declarations() -> None:
    known = graph_topics()
    for name in ('/mill/x/state', '/mill/z/joint_command', '/mill/planned_path', '/diagnostics'):
        assert name in known
    assert '/robot_description' in known and '/joint_states' in known and '/tf' in known


def test_the_rviz_config_parses_and_names_only_graph_topics() -> None:
    config = yaml.safe_load(RVIZ.read_text())
    displays = config['Visualization Manager']['Displays']
    classes = [d['Class'] for d in displays]
    for kind in ('RobotModel', 'TF', 'Path'):
        assert f'rviz_default_plugins/{kind}' in classes
    assert config['Visualization Manager']['Global Options']['Fixed Frame'] == 'mill_base'
    named = named_topics(config)
    assert named <= graph_topics(), named - graph_topics()
    wanted = {topics.ROBOT_DESCRIPTION, topics.PLANNED_PATH, topics.TOOL_TRACE}
    assert {topics.qualify(t) for t in wanted} <= named
    # the latched topics are asked for with transient local, or RViz would miss them
    for display in displays:
        topic = display.get('Topic') or display.get('Description Topic')
        if topic and topic['Value'] in (
            topics.qualify(topics.PLANNED_PATH),
            topics.qualify(topics.ROBOT_DESCRIPTION),
        ):
            assert topic['Durability Policy'] == 'Transient Local', display['Name']


def test_the_foxglove_layout_parses_and_names_only_graph_topics() -> None:
    layout = json.loads(FOXGLOVE.read_text())
    panels = layout['configById']
    named = named_topics(panels)
    assert named <= graph_topics(), named - graph_topics()
    wanted = {
        topics.ROBOT_DESCRIPTION,
        topics.PLANNED_PATH,
        topics.TOOL_TRACE,
        topics.JOINT_STATES,
        topics.DIAGNOSTICS,
    }
    assert {topics.qualify(t) for t in wanted} <= named

    # every panel the layout places is configured, and every configured one placed
    def leaves(node: Any) -> Iterator[str]:
        if isinstance(node, dict):
            for key in ('first', 'second'):
                yield from leaves(node[key])
        else:
            yield node

    placed = set(leaves(layout['layout']))
    assert placed == set(panels)
