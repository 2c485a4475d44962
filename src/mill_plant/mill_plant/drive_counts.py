"""What the drive counts per axis for its status (`<node>: lockstep` / `realtime`). ROS-free.

Per step it counts what the machine did to each axis's effort (mill_plant.axis_plant's
`StepReport`): braked for want of a finite command (a fault, reported when it first happens;
not while the drive holds an axis before its first command) or clipped to the axis's limit.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence

from mill_plant.axis_plant import StepReport


class DriveCounts:
    def __init__(self, axes: Sequence[str]) -> None:
        self.axes = list(axes)
        self.faults = dict.fromkeys(self.axes, 0)  # steps braked: no finite command to apply
        self.saturations = dict.fromkeys(self.axes, 0)  # steps with the effort clipped

    def step(
        self, report: StepReport, order: Sequence[str], held: Collection[str] = ()
    ) -> list[str]:
        """Count one step's report (its flags in the order of `order`); held: axes held braked
        before their first command (not a fault). Returns the axes braked for the first time."""
        first = []
        for axis in self.axes:
            i = order.index(axis)
            if report.faulted[i] and axis not in held:
                self.faults[axis] += 1
                if self.faults[axis] == 1:
                    first.append(axis)
            if report.saturated[i]:
                self.saturations[axis] += 1
        return first

    def values(
        self, invalid_commands: Mapping[str, int], machine_faults: Mapping[str, str]
    ) -> dict[str, object]:
        """The per-axis values of the status: the counts, the brake requests (invalid
        commands) and what the machine says is wrong (its `faults()`)."""
        values: dict[str, object] = {}
        for axis in self.axes:
            values[f'{axis}.faults'] = self.faults[axis]
            values[f'{axis}.saturations'] = self.saturations[axis]
            values[f'{axis}.invalid_commands'] = invalid_commands[axis]
        for axis, text in machine_faults.items():
            values[f'{axis}.fault'] = text
        return values
