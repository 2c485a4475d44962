"""Harmonics of a base frequency, as both Maharof 2018 sides take them (ROS-free).

The plant's harmonic cutting force (mill_plant.harmonic_force) and the DFO's resonators
(mill_observers.dfo) list the same multiples m_i of f_0 = spindle_speed/60·teeth, checked
by the one function here so that what one accepts the other does.
"""

from __future__ import annotations

from typing import Any

from mill_common.parameters import number_list, positive


def harmonic_multiples(value: Any) -> str | None:
    """Check of a list of harmonic multiples m_i: positive numbers, at least one, none twice."""
    reason = number_list(each=positive)(value)
    if reason:
        return reason
    if not value:
        return 'must list at least one harmonic'
    if len(set(value)) != len(value):
        return 'must not repeat a harmonic'
    return None
