"""Who publishes on a drive's topics besides their owners (docs/reliability.md, "one owner").

A command topic belongs to its axis's controller, a state topic to the drive itself. A
foreign sender is found two ways: by a message it sent (`message_from`), and by the ROS
graph, once a second, even if it never sends (`look`). Each foreign publisher is named once.
Two live publishers claiming an owner's name (mill_common.graph_owner: both speak) are
`contested`: named, both, in the status from then on.
"""

from __future__ import annotations

from collections.abc import Mapping

from diagnostic_msgs.msg import DiagnosticStatus
from mill_common.diagnostics import Diagnostics
from rclpy.node import Node

from mill_common import topics

OWNERSHIP_PART = 'ownership'  # the drive's status `<node>: ownership`
UNKNOWN_NODE = '_NODE_NAME_UNKNOWN_'  # an endpoint whose node discovery has not named yet


class Ownership:
    def __init__(
        self, node: Node, owners: Mapping[str, str], more: Mapping[str, str] | None = None
    ) -> None:
        """owners: axis -> the node its commands must come from ('' = anyone, not checked);
        more: other owned topics -> their owner (ros2_control's pair, mill_plant.topic_pair)."""
        self._node = node
        self._owned = {
            topic: owner
            for axis, controller in owners.items()
            if controller
            for topic, owner in (
                (topics.joint_command(axis), controller),
                (topics.state(axis), node.get_name()),
            )
        }
        self._owned.update({t: o for t, o in (more or {}).items() if o})
        self.foreign: dict[str, set[str]] = {}  # topic -> foreign publishers seen
        self.foreign_messages = 0
        self.contests: dict[str, tuple[str, tuple[str, ...]]] = {}  # topic -> (owner, claimants)
        self._counts: dict[str, int] = {}  # topic -> publishers at the last look

    def message_from(self, topic: str, who: str) -> bool:
        """A message from a foreign sender; True if it is named for the first time."""
        self.foreign_messages += 1
        return self._note(topic, who)

    def contested(self, topic: str, owner: str, claimants: tuple[str, ...]) -> None:
        """These publishers of `topic`, all alive, claim the name `owner`."""
        self.contests[topic] = (owner, claimants)

    def look(self) -> list[tuple[str, str]]:
        """Foreign publishers the graph shows for the first time: (topic, node)."""
        new = []
        for topic, owner in self._owned.items():
            for name in self._new_publishers(topic):
                if name not in (owner, UNKNOWN_NODE) and self._note(topic, name):
                    new.append((topic, name))
        return new

    def status(self, diagnostics: Diagnostics) -> DiagnosticStatus | None:
        """ERROR naming every foreign publisher seen and every contested owner's name, or
        None while there is none. Values: `foreign_messages`; `contested` (one line per
        topic: 'topic: owner: claimant; claimant')."""
        if not self.foreign and not self.contests:
            return None
        parts: list[str] = []
        values: dict[str, object] = {
            'foreign_messages': self.foreign_messages,
            'foreign_publishers': sum(len(w) for w in self.foreign.values()),
        }
        if self.foreign:
            seen = '; '.join(f'{t}: {", ".join(sorted(w))}' for t, w in self.foreign.items())
            parts.append(f'foreign publishers ignored: {seen}')
        if self.contests:
            said = [f'{t}: {o}: {"; ".join(c)}' for t, (o, c) in sorted(self.contests.items())]
            parts.append(f'owner claimed by two publishers, both refused: {" | ".join(said)}')
            values['contested'] = ' | '.join(said)
        return diagnostics.status(DiagnosticStatus.ERROR, OWNERSHIP_PART, '; '.join(parts), values)

    def _note(self, topic: str, who: str) -> bool:
        seen = self.foreign.setdefault(topic, set())
        if who in seen:
            return False
        seen.add(who)
        return True

    def _new_publishers(self, topic: str) -> list[str]:
        """The publishers of `topic` if their number changed since the last look, else none:
        counting them costs a tenth of naming them, and this runs in the drive's thread."""
        count = self._node.count_publishers(topic)
        if self._counts.get(topic) == count:
            return []
        names = [info.node_name for info in self._node.get_publishers_info_by_topic(topic)]
        if UNKNOWN_NODE not in names:  # a name discovery has not given yet: look again
            self._counts[topic] = count
        return names
