"""The machine's URDF: three prismatic joints x, y, z in a chain, limits the travel."""

from __future__ import annotations

import math
import sys
from xml.etree import ElementTree

import pytest
from mill_common.machine_urdf import BASE_LINK, TOOL_LINK, joint_limits, machine_urdf


def _joints(urdf: str) -> dict[str, ElementTree.Element]:
    return {j.get('name', ''): j for j in ElementTree.fromstring(urdf).iter('joint')}


def test_every_axis_is_a_prismatic_joint_whose_limits_are_the_travel() -> None:
    lo, hi = [-0.2, -0.3, -0.1], [0.25, 0.35, 0.05]
    urdf = machine_urdf(joint_limits(lo, hi, 0.08, [12.0, 11.0, math.inf]))
    joints = _joints(urdf)
    assert list(joints) == ['x', 'y', 'z']
    chain = [BASE_LINK]
    for i, joint in enumerate(joints.values()):
        assert joint.get('type') == 'prismatic'
        assert joint.find('parent').get('link') == chain[-1]  # type: ignore[union-attr]
        chain.append(joint.find('child').get('link'))  # type: ignore[union-attr]
        direction = [float(v) for v in joint.find('axis').get('xyz').split()]  # type: ignore[union-attr]
        assert direction == [1.0 if k == i else 0.0 for k in range(3)]
        limit = joint.find('limit')
        assert limit is not None
        assert float(limit.get('lower', 'nan')) == lo[i]
        assert float(limit.get('upper', 'nan')) == hi[i]
        assert float(limit.get('velocity', 'nan')) == 0.08
    assert chain[-1] == TOOL_LINK
    links = [link.get('name') for link in ElementTree.fromstring(urdf).iter('link')]
    assert sorted(links) == sorted(chain)
    efforts = [float(j.find('limit').get('effort')) for j in joints.values()]  # type: ignore[union-attr]
    assert efforts == [12.0, 11.0, sys.float_info.max]  # .inf: no limit, a finite number


def test_a_travel_or_list_the_urdf_cannot_hold_is_refused() -> None:
    with pytest.raises(ValueError, match=r'travel of axis y: min 0\.5 exceeds max 0\.1'):
        joint_limits([0, 0.5, 0], [1, 0.1, 1], 0.1, [1, 1, 1])
    with pytest.raises(ValueError, match='max_torque must have 3 values, got 2'):
        joint_limits([0, 0, 0], [1, 1, 1], 0.1, [1, 1])


def test_the_frames_of_a_machine_in_a_namespace_carry_it() -> None:
    from mill_common.machine_urdf import frame, frame_prefix

    prefixes = (frame_prefix('/'), frame_prefix(''), frame_prefix('machine_a'))
    assert prefixes == ('', '', 'machine_a/')
    assert frame(BASE_LINK, '/shop/m2') == 'shop/m2/mill_base'
    assert frame(TOOL_LINK, '/') == 'tool'
