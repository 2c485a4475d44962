"""What an axis controller says on /diagnostics and in its log: its following error, a trip
and its reset, a law switch (`<node>: following error`, `<node>: switch`)."""

from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticStatus
from mill_common.diagnostics import Diagnostics
from mill_common.timing import Timing

from mill_controllers.switching import SwitchRecord
from mill_controllers.trip import FollowingErrorTrip, Trip

TRIP_PART = 'following error'


class AxisReports:
    def __init__(self, diagnostics: Diagnostics, axis: str, timing: Timing) -> None:
        self.diagnostics, self.axis, self.timing = diagnostics, axis, timing

    def _when(self, t: float) -> str:
        return self.timing.when(round(t * 1e9))

    def status(
        self, trip: FollowingErrorTrip, late_references: int
    ) -> tuple[bytes, str, str, dict[str, object]]:
        """The following-error status: running, or the trip (level, part, message, values)."""
        values: dict[str, object] = {
            'axis': self.axis,  # read by mill_analysis.events
            'following_error_limit_m': trip.limit,
            'late_references': late_references,
        }
        if trip.trip is None:
            return DiagnosticStatus.OK, TRIP_PART, f'axis {self.axis}: running', values
        values.update({'trip_time_s': trip.trip.time, 'trip_error_m': trip.trip.error})
        if trip.trip.cause:
            values['trip_cause'] = trip.trip.cause
        text = trip.trip.describe(self.axis, self._when(trip.trip.time))
        return DiagnosticStatus.ERROR, TRIP_PART, text, values

    def tripped(self, ns: int, trip: FollowingErrorTrip, late_references: int) -> None:
        self.diagnostics.report(ns, *self.status(trip, late_references))

    def cleared(self, ns: int, cleared: Trip | None, how: str, trip: FollowingErrorTrip) -> None:
        if cleared is not None:
            when = self._when(cleared.time)
            kind = 'trip' if cleared.cause else 'following-error trip'
            message = f'axis {self.axis}: {kind} {when} cleared by {how}'
            values = self.status(trip, 0)[3]
            self.diagnostics.report(ns, DiagnosticStatus.WARN, TRIP_PART, message, values)

    def switched(self, ns: int, law: str, record: SwitchRecord, blend_time: float) -> None:
        message = (
            f'switched to {law} {self.timing.when(ns)}: output {record.old_output:.6g} (new '
            f'law alone {record.new_output:.6g}), offset fades over {blend_time:g} s'
        )
        values = {
            'controller': law,
            'time': repr(record.time),
            'old_output': repr(record.old_output),
            'new_output': repr(record.new_output),
        }
        self.diagnostics.report(ns, DiagnosticStatus.OK, 'switch', message, values)
