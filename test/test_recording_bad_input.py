"""A bad message during a real recording (issue 25): the recorder drops it, counts it, records
on, and the bag is closed whole.

A node of the test publishes a sensor_msgs/JointState with header.stamp.sec = -1, as the
outside attack did: on an unrelated topic during `run_scenario --record` (the run's monitor
records every topic of the domain), and on a recorded topic and an unrelated one while the
standalone `recorder` records a fake plant. Before the fix the first such message ended the
recording with three tracebacks and left the bag open.
"""

from __future__ import annotations

import json
import signal
import time
from pathlib import Path

import pytest
import yaml
from mill_bag.reader import open_bag
from mill_bag.recorder import DROPPED
from mill_bag.writer import RESERVE_NAME
from mill_common.ros import DATA_QOS
from sensor_msgs.msg import JointState

from mill_common import topics
from test.conftest import ros_node, start_scenario, wait_until
from test.test_recording import FakePlant, both_readers, metadata_counts

Q = topics.qualify
T_NS = 1_000_000
UNRELATED = '/unrelated/joint_states'


def negative_stamp() -> JointState:
    msg = JointState(name=['x'], position=[0.0])
    msg.header.stamp.sec = -1
    return msg


def assert_closed_whole(bag: Path, dropped: int) -> dict[str, int]:
    """The bag is closed (no reserve, rosbags and mcap read it alike) and notes its drops."""
    assert not (bag / RESERVE_NAME).exists()
    by_rosbags, by_mcap, _ = both_readers(bag)  # rosbags refuses a file without footer
    assert by_rosbags == by_mcap == metadata_counts(bag)
    assert open_bag(bag).noted_counts(DROPPED) == {'negative stamp': dropped}
    return dict(by_mcap)


@pytest.mark.system
def test_a_negative_stamp_does_not_end_a_recorded_run(ros_env, tmp_path) -> None:
    out = tmp_path / 'run'
    runner = start_scenario(
        ros_env, 'slotting', '--duration', '1', '--record', '--quiet', '--output', str(out)
    )
    sent = 0
    try:
        with ros_node('hostile') as (node, executor):
            pub = node.create_publisher(JointState, UNRELATED, DATA_QOS)
            while runner.poll() is None:
                pub.publish(negative_stamp())
                sent += 1
                executor.spin_once(timeout_sec=0.05)
        stdout, stderr = runner.communicate(timeout=600)
    finally:
        if runner.poll() is None:
            runner.kill()
            runner.communicate()
    assert runner.returncode == 0, stderr[-3000:]
    assert 'Traceback' not in stderr and 'FATAL' not in stderr, stderr[-3000:]
    summary = json.loads((out / 'summary.json').read_text())
    dropped = summary['bag']['dropped']['negative stamp']
    assert 1 <= dropped <= sent and summary['bag']['dropped'] == {'negative stamp': dropped}
    assert f'; {dropped} dropped (negative stamp {dropped})' in stdout
    assert f'dropped a message on {UNRELATED}: negative stamp (sec -1)' in stderr
    assert summary['missing_samples'] == {}  # the run's own topics are whole
    counts = assert_closed_whole(out / 'bag', dropped)
    assert UNRELATED not in counts  # its only messages were the bad ones
    assert sum(counts.values()) == summary['bag']['messages']


@pytest.mark.system
def test_the_recorder_drops_a_negative_stamp_and_records_on(start_node, tmp_path) -> None:
    bag = tmp_path / 'bag'
    recorder = start_node(
        'mill_bag.recorder',
        'recorder',
        *('-p', f'output:={bag}', '-p', 'use_sim_time:=true'),
        params_file=False,
    )
    n, state = 300, Q(topics.state('x'))
    with ros_node('fake_plant') as (node, _executor):
        plant = FakePlant(node)
        hostile = node.create_publisher(JointState, UNRELATED, DATA_QOS)
        bad_state = node.create_publisher(JointState, topics.state('x'), DATA_QOS)
        assert wait_until(plant.matched, 60), 'the recorder never subscribed'
        assert wait_until(lambda: hostile.get_subscription_count() >= 1, 60)
        for k in range(n):
            plant.publish(k)
            if k % 30 == 0:  # ten of each
                hostile.publish(negative_stamp())
                bad_state.publish(negative_stamp())
            time.sleep(0.001)
        expected = {state: n, Q(topics.CUTTING_FORCE): n, topics.CLOCK: n // 10}

        def recorded() -> dict[str, int]:
            return {t: c for t, c in metadata_counts(bag).items() if t in expected}

        assert wait_until(lambda: recorded() == expected, 30), metadata_counts(bag)
    assert recorder.alive()
    recorder.proc.send_signal(signal.SIGINT)
    code, _out, err = recorder.wait(timeout=30)
    assert code == 0, err
    assert 'Traceback' not in err, err
    assert f'dropped a message on {UNRELATED}: negative stamp (sec -1); 1 so far' in err or (
        f'dropped a message on {state}: negative stamp (sec -1); 1 so far' in err
    )
    last = err.strip().splitlines()[-1]
    assert last.startswith(f'recorder: bag {bag}: ') and last.endswith(
        '; 20 dropped (negative stamp 20)'
    )
    counts = assert_closed_whole(bag, 20)
    assert {t: counts[t] for t in expected} == expected and UNRELATED not in counts
    meta = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['custom_data'][DROPPED] == '{"negative stamp": 20}'
