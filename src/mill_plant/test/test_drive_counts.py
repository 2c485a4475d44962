"""The drive's per-axis counts: faults (said once, not while an axis is held before its first
command), saturations, and the values of its status."""

from __future__ import annotations

from mill_plant.axis_plant import StepReport
from mill_plant.drive_counts import DriveCounts

ORDER = ('x', 'y', 'z')


def flags(axes: str) -> tuple[bool, bool, bool]:
    return ('x' in axes, 'y' in axes, 'z' in axes)


def report(faulted: str = '', saturated: str = '') -> StepReport:
    return StepReport(saturated=flags(saturated), faulted=flags(faulted))


def test_a_fault_is_counted_every_step_and_returned_only_the_first_time() -> None:
    counts = DriveCounts(['x', 'z'])  # a machine without y: its flags are not read
    assert counts.step(report(faulted='xyz'), ORDER) == ['x', 'z']
    assert counts.step(report(faulted='xz'), ORDER) == []
    assert counts.step(report(faulted='x', saturated='yz'), ORDER) == []
    assert counts.faults == {'x': 3, 'z': 2}
    assert counts.saturations == {'x': 0, 'z': 1}


def test_an_axis_held_before_its_first_command_is_not_faulted() -> None:
    counts = DriveCounts(['x', 'y'])
    for _ in range(5):
        assert counts.step(report(faulted='xy'), ORDER, held=['x', 'y']) == []
    assert counts.step(report(faulted='xy'), ORDER, held=['x']) == ['y']
    assert counts.step(report(faulted='xy'), ORDER) == ['x']  # its first command came
    assert counts.faults == {'x': 1, 'y': 2}


def test_the_status_values_name_each_axis_then_what_the_machine_says() -> None:
    counts = DriveCounts(['x', 'y'])
    counts.step(report(faulted='y', saturated='x'), ORDER)
    counts.step(report(saturated='x'), ORDER)
    values = counts.values({'x': 0, 'y': 7}, {'y': 'amplifier fault'})
    assert list(values.items()) == [
        ('x.faults', 0),
        ('x.saturations', 2),
        ('x.invalid_commands', 0),
        ('y.faults', 1),
        ('y.saturations', 0),
        ('y.invalid_commands', 7),
        ('y.fault', 'amplifier fault'),
    ]
    assert 'y.fault' not in counts.values({'x': 0, 'y': 0}, {})
