"""Harmonics of a base frequency, as both Maharof 2018 sides take them (ROS-free).

The plant's harmonic cutting force (mill_plant.harmonic_force) and the DFO's resonators
(mill_observers.dfo) list the same multiples m_i of f_0 = spindle_speed/60·teeth, checked
by the one function here so that what one accepts the other does.
"""

from __future__ import annotations

from typing import Any

from mill_common.parameters import number_list, positive

# Each harmonic is a resonator of the observer (its state and its gains grow with their
# count squared) and a term of the force: Maharof uses 3.
MAX_HARMONICS = 32


def harmonic_multiples(value: Any) -> str | None:
    """Check of a list of harmonic multiples m_i: positive numbers, at least one and at most
    MAX_HARMONICS, none twice."""
    reason = number_list(each=positive)(value)
    if reason:
        return reason
    if not value:
        return 'must list at least one harmonic'
    if len(value) > MAX_HARMONICS:
        return f'must list at most {MAX_HARMONICS} harmonics, got {len(value)}'
    if len(set(value)) != len(value):
        return 'must not repeat a harmonic'
    return None
