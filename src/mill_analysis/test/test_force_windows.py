"""Mean force and override of a recorded force-controlled run, per time window."""

from __future__ import annotations

import numpy as np
import pytest
from mill_analysis.force_windows import main, state_windows
from mill_bag.types import typestore
from mill_bag.writer import BagWriter

from mill_common import topics


def test_state_windows_average_a_recorded_run(tmp_path) -> None:
    store = typestore()
    js, time_msg, head = (
        store.types[n]
        for n in (
            'sensor_msgs/msg/JointState',
            'builtin_interfaces/msg/Time',
            'std_msgs/msg/Header',
        )
    )
    w = BagWriter(tmp_path / 'bag')
    state = w.add_topic(
        topics.qualify(topics.FORCE_CONTROL_STATE), 'sensor_msgs/msg/JointState', []
    )
    names = ['force', 'reference', 'feed_command', 'override', 'beta', 'depth']
    for k in range(20):  # 0.1 s apart: force k, override k/100
        ns = k * 100_000_000
        msg = js(
            header=head(stamp=time_msg(sec=ns // 10**9, nanosec=ns % 10**9), frame_id=''),
            name=names,
            position=np.array([k, 300.0, 0.0, k / 100, 0.0, 5.0]),
            velocity=np.zeros(0),
            effort=np.zeros(0),
        )
        w.write(state, ns, ns, bytes(store.serialize_cdr(msg, 'sensor_msgs/msg/JointState')))
    w.close()
    rows = state_windows(tmp_path / 'bag', [0.0, 1.0, 1.5, 5.0])
    assert [r[2] for r in rows] == [10, 5, 5]
    assert rows[0][3] == pytest.approx(4.5) and rows[0][4] == pytest.approx(0.045)
    assert rows[1][3] == pytest.approx(12.0) and rows[2][3] == pytest.approx(17.0)
    assert main([str(tmp_path / 'bag'), '0', '1']) == 0
    assert main([str(tmp_path / 'missing'), '0', '1']) == 1
