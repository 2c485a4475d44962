"""What a drive (mill_plant.drive_node) says on /diagnostics and in its log.

- a dropped message: a WARN `<node>: inputs` naming the topic and the sender, at most once a
  second per topic, with the counts so far;
- a foreign publisher on its topics (mill_plant.ownership): named once, with the status;
- an axis's events (`<node>: <axis> axis`): a brake, a stop, a release, a silence;
- its status (`<node>: <part of its timing>`, and `<node>: ownership` while a foreign
  publisher is seen): the running one once a second, a fault at once.
"""

from __future__ import annotations

import time
from typing import Any, ClassVar, Protocol

from diagnostic_msgs.msg import DiagnosticStatus
from mill_common.checks import DropCounter, Rejected
from mill_common.diagnostics import Diagnostics
from mill_common.timebase import seconds

from mill_plant.backend import DriveBackend
from mill_plant.command_intake import CommandIntake
from mill_plant.drive_counts import DriveCounts
from mill_plant.ownership import Ownership


class Clocked(Protocol):
    """What the reports read of the drive's timing (mill_plant.drive_cycle.DriveCycle, which
    imports this module)."""

    STATUS: ClassVar[str]
    k: int
    active: bool  # applying commands

    def stamp_now(self) -> int: ...

    def status_values(self) -> dict[str, object]: ...


class Reported(Protocol):
    """What the reports read of the drive front end (mill_plant.drive_node.DriveNode)."""

    @property
    def cycle(self) -> Clocked: ...

    diagnostics: Diagnostics
    backend: DriveBackend | None
    counts: DriveCounts
    intake: CommandIntake
    ownership: Ownership | None
    dt_ns: int

    def get_logger(self) -> Any: ...


class DriveReports:
    def __init__(self, drive: Reported) -> None:
        self.drive = drive
        self.drops = DropCounter()  # over the node's life, as its wall time
        self.wall_start = time.monotonic()
        self.next_status = 0.0  # when the running status is due (steady time)

    def drop(self, topic: str, problem: Rejected, sender: str = '') -> None:
        d = self.drive
        if self.drops.drop(topic, problem, time.monotonic()):
            text = (
                f'dropped a message on {topic} from {sender or "an unnamed publisher"}: '
                f'{problem.reason} ({self.drops.counts[topic]} so far)'
            )
            d.get_logger().warning(text)
            counts = dict(self.drops.counts)
            status = d.diagnostics.status(DiagnosticStatus.WARN, 'inputs', text, counts)
            d.diagnostics.publish(d.cycle.stamp_now(), [status])

    def foreign(self, topic: str, who: str) -> None:
        self.drive.get_logger().error(
            f'foreign publisher {who} on {topic}: its messages are ignored'
        )
        self.status(force=True)

    def contested(self, topic: str, owner: str, claimants: tuple[str, ...]) -> None:
        self.drive.get_logger().error(
            f'{len(claimants)} publishers on {topic} claim to be {owner}: '
            f'{"; ".join(claimants)}: both refused, the axis brakes'
        )
        self.status(force=True)

    def axis(self, axis: str, level: bytes, message: str) -> None:
        """The status `<node>: <axis> axis`, and the log."""
        d = self.drive
        values = {'step': d.cycle.k}
        stamp = d.cycle.stamp_now()
        d.diagnostics.report(stamp, level, f'{axis} axis', f'axis {axis}: {message}', values)

    def periodic(self, now: float) -> None:
        """From the watchdog: once a second, the graph's new foreign publishers on the
        drive's topics (besides their owners) and the running status."""
        if now >= self.next_status:
            if self.drive.ownership is not None:
                for topic, who in self.drive.ownership.look():
                    self.foreign(topic, who)
            self.status()

    def status(
        self, force: bool = False, message: str | None = None, level: bytes | None = None
    ) -> None:
        """The drive's status; `message` (a fault, ERROR unless `level` says otherwise) is
        published at once, the running status once a second."""
        d = self.drive
        now = time.monotonic()
        if not force and now < self.next_status:
            return
        self.next_status = now + 1.0
        k = d.cycle.k
        values: dict[str, object] = {
            'step': k,
            'time': seconds(k * d.dt_ns),
            'wall_s': now - self.wall_start,
            'active': d.cycle.active,
            'dropped': self.drops.total,
            **d.cycle.status_values(),
        }
        faults = d.backend.faults() if d.backend is not None else {}
        values.update(d.counts.values(d.intake.invalid_commands, faults))
        if message is None:  # the running status: ERROR while the machine reports a fault
            level = DiagnosticStatus.ERROR if faults else DiagnosticStatus.OK
        elif level is None:
            level = DiagnosticStatus.ERROR
        text = message or ('running' if d.cycle.active else 'waiting')
        statuses = [d.diagnostics.status(level, d.cycle.STATUS, text, values)]
        foreign = d.ownership.status(d.diagnostics) if d.ownership is not None else None
        if foreign is not None:
            statuses.append(foreign)
        d.diagnostics.publish(d.cycle.stamp_now(), statuses)
