"""A verdict under several readings of a paper. ROS-free, pure.

A paper leaves settings open (a sample period, the unit of a constant, what an index
compares); each reading is a scenario override, and each combination of readings a run.
A claim's verdict is stated for every combination that was run: where they all agree it is
that verdict; where they differ it is "depends on …", naming every reading whose change
alone flips it somewhere. A verdict that flips is never reported as agreeing.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

AGREES, DISAGREES = 'agrees', 'DISAGREES'


def verdict(holds: bool) -> str:
    return AGREES if holds else DISAGREES


def flips(verdicts: Mapping[tuple[str, ...], bool], axes: Sequence[str]) -> list[str]:
    """The readings (names in `axes`, one per position of the keys) whose change alone
    flips the verdict between two combinations that were run."""
    out = []
    for i, axis in enumerate(axes):
        for a, va in verdicts.items():
            if any(
                b[:i] == a[:i] and b[i + 1 :] == a[i + 1 :] and b[i] != a[i] and vb != va
                for b, vb in verdicts.items()
            ):
                out.append(axis)
                break
    return out


def overall(verdicts: Mapping[tuple[str, ...], bool], axes: Sequence[str]) -> str:
    """'agrees' / 'DISAGREES' when every combination says so, else 'depends on A, B'."""
    values = set(verdicts.values())
    if len(values) == 1:
        return verdict(values.pop())
    return 'depends on ' + ', '.join(flips(verdicts, axes) or axes)
