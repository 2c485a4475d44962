"""A node's inputs under watch: bad messages dropped and counted, silence reported.

Every node that subscribes keeps an `InputGuard`. Its callbacks check each message
(mill_common.checks) and tell the guard what they dropped (`drop`) and what they used
(`heard`). A steady-clock timer (`tick`, four times a second) does the rest:

- an input quiet for `warn_after` seconds is a WARN, for `error_after` an ERROR, on
  /diagnostics and in the log, naming the topic and the node expected to publish it; an
  input that has never been heard is reported as waiting (the graph may still be starting),
  and until the node has stepped past its first sample a silence is no WARN either: in
  lockstep the plant holds step 0 (offering it again once a second) until discovery has
  joined every node, which is start-up, not a fault; an ERROR still ends a start that
  never comes;
- when an outage ends, its length is logged and reported;
- in lockstep, an input silent for `error_after` ends the node with that message (exit 3):
  nobody hangs silently; in real time the node keeps running and keeps reporting;
- dropped messages are counted per topic and reported at most once a second each.

The status goes to /diagnostics as `<node>: inputs` every second and at once on a change
(mill_common.diagnostics: the node's one publisher there).
"""

from __future__ import annotations

import time
from collections.abc import Callable

from diagnostic_msgs.msg import DiagnosticStatus
from rclpy.clock import Clock, ClockType
from rclpy.node import Node

from mill_common.checks import DropCounter, Rejected
from mill_common.diagnostics import Diagnostics
from mill_common.node_main import request_exit
from mill_common.watch import InputWatch, Level

LEVELS = {
    Level.OK: DiagnosticStatus.OK,
    Level.WARN: DiagnosticStatus.WARN,
    Level.ERROR: DiagnosticStatus.ERROR,
}


class InputGuard:
    def __init__(
        self,
        node: Node,
        warn_after: Callable[[], float],
        error_after: Callable[[], float],
        exit_on_silence: bool,
        stamp_ns: Callable[[], int],
        extra: Callable[[], tuple[bytes, str, str, dict[str, object]]] | None = None,
    ) -> None:
        self.node = node
        self._warn_after = warn_after
        self._error_after = error_after
        self.exit_on_silence = exit_on_silence
        self._stamp_ns = stamp_ns
        # The node's own state, sent with the inputs' status: (level, part, message, values).
        self._extra = extra
        self.watches: dict[str, InputWatch] = {}
        self.drops = DropCounter()
        self._levels: dict[str, Level] = {}
        self._stamps_seen: set[int] = set()  # the node's stamps until it is past its first
        self._next_status = 0.0
        # The node's one publisher on /diagnostics: its other statuses go out here too.
        self.diagnostics = Diagnostics(node)
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        node.create_timer(0.25, self.tick, clock=steady)

    def watch(self, topic: str, publisher: str | None = None) -> InputWatch:
        """Watch an input; publisher None: named from the ROS graph at its first message."""
        w = InputWatch(topic, publisher or '', self._warn_after(), self._error_after())
        self.watches[topic] = w
        return w

    def heard(self, topic: str) -> None:
        w = self.watches[topic]
        if not w.publisher:  # the nodes publishing it now, while they are alive to be named
            infos = self.node.get_publishers_info_by_topic(topic)
            names = sorted({i.node_name for i in infos} - {'_NODE_NAME_UNKNOWN_'})
            w.publisher = ', '.join(names) or 'a node discovery has not named'
        ended = w.heard(time.monotonic(), counts=self.started)
        if ended is not None:
            self._levels[topic] = Level.OK  # the status sent now says it is back, not silent
            self.node.get_logger().info(
                f'{topic} (from {w.publisher}) back after {ended:.2f} s of silence'
            )
            self._publish(force=True)

    def drop(self, topic: str, rejected: Rejected, sender: str = '') -> None:
        if self.drops.drop(topic, rejected, time.monotonic()):
            who = f' from {sender}' if sender else ''
            self.node.get_logger().warning(
                f'dropped a message on {topic}{who}: {rejected.reason} '
                f'({self.drops.counts[topic]} so far)'
            )
            self._publish(force=True)

    def contested(self, topic: str, owner: str, claimants: tuple[str, ...], then: str = '') -> None:
        """Two or more publishers of an input claim its owner's name (mill_common.
        graph_owner): both refused; logged, and an ERROR `ownership` on /diagnostics at the
        node's stamp. then: what else follows (', the axis brakes')."""
        named = '; '.join(claimants)
        self.node.get_logger().error(
            f'{len(claimants)} publishers on {topic} claim to be {owner}: {named}: '
            f'both refused{then}'
        )
        said = f'{topic}: {owner}: {named}'
        values = {'foreign_messages': 0, 'foreign_publishers': 0, 'contested': said}
        message = f'owner claimed by two publishers, both refused{then}: {said}'
        ns = self._stamp_ns()
        self.diagnostics.report(ns, DiagnosticStatus.ERROR, 'ownership', message, values)

    @property
    def started(self) -> bool:
        """The node has stepped past its first sample (its stamp has moved on)."""
        if len(self._stamps_seen) < 2:
            self._stamps_seen.add(self._stamp_ns())
        return len(self._stamps_seen) >= 2

    def tick(self) -> None:
        now = time.monotonic()
        silent = False
        started = self.started
        for topic, w in self.watches.items():
            w.warn_after, w.error_after = self._warn_after(), self._error_after()
            level = Level.OK if w.waiting else w.level(now)
            if level is Level.WARN and not started:
                level = Level.OK  # start-up (see above)
            old = self._levels.get(topic, Level.OK)
            self._levels[topic] = level
            if level > old:
                text = w.describe(now)
                if level is Level.ERROR:
                    self.node.get_logger().error(text)
                else:
                    self.node.get_logger().warning(text)
                self._publish(force=True)
            silent = silent or level is Level.ERROR
        if silent and self.exit_on_silence:
            # A dead peer silences what it fed to other nodes as well: name every quiet input,
            # not only the first one over the limit.
            quiet = [w.describe(now) for t, w in self.watches.items() if self._levels[t]]
            request_exit(self.node, 3, '; '.join(quiet))
        self._publish()

    def level(self) -> Level:
        return max(self._levels.values(), default=Level.OK)

    def _publish(self, force: bool = False) -> None:
        now = time.monotonic()
        if not force and now < self._next_status:
            return
        self._next_status = now + 1.0
        values: dict[str, object] = {}
        quiet = []
        for topic, w in self.watches.items():
            values[f'{topic}.silence_s'] = round(w.silence(now), 3)
            values[f'{topic}.dropped'] = self.drops.counts.get(topic, 0)
            values[f'{topic}.outages'] = w.outages
            if w.outages:
                values[f'{topic}.last_outage_s'] = round(w.last_outage, 3)
            if self._levels.get(topic, Level.OK) is not Level.OK:
                quiet.append(w.describe(now))
            elif w.waiting:
                values[f'{topic}.waiting'] = True
        level = LEVELS[self.level()]
        message = '; '.join(quiet) or 'inputs arriving'
        if self.drops.total:
            last = '; '.join(f'{t}: {r}' for t, r in self.drops.last_reason.items())
            message += f'; dropped {self.drops.total} bad messages (last: {last})'
            level = max(level, DiagnosticStatus.WARN)
        d = self.diagnostics
        statuses = [d.status(level, 'inputs', message, values)]
        if self._extra is not None:
            statuses.append(d.status(*self._extra()))
        d.publish(self._stamp_ns(), statuses)
