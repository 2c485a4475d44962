"""The bag format without a ROS graph: our bags open in rosbags and in mcap + mcap_ros2, a
killed recording loses only its unflushed tail and can be recovered, a type missing from the
typestore is loaded from its .msg file, and the fast JointState reader equals rosbags."""

from __future__ import annotations

import math
import subprocess
import sys
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mill_bag.cdr import joint_state_cdr
from mill_bag.errors import BagError
from mill_bag.reader import Bag, open_bag
from mill_bag.recover import recover
from mill_bag.types import (
    CLOCK,
    HEADER,
    JOINT_STATE,
    STRING,
    TIME,
    WRENCH_STAMPED,
    decode,
    message_definition,
    sim_stamped,
    typestore,
)
from mill_bag.writer import BagWriter

TS = typestore()
T = TS.types
QOS = [
    {
        'history': 'unknown',
        'depth': 0,
        'reliability': 'reliable',
        'durability': 'volatile',
        'deadline': {'sec': 9223372036, 'nsec': 854775807},
        'lifespan': {'sec': 9223372036, 'nsec': 854775807},
        'liveliness': 'automatic',
        'liveliness_lease_duration': {'sec': 9223372036, 'nsec': 854775807},
        'avoid_ros_namespace_conventions': False,
    }
]
WALL0 = 1_700_000_000_000_000_000
STATE, FORCE, CLOCK_TOPIC = '/robot/x/state', '/robot/force', '/clock'


def stamp(ns: int) -> Any:
    return T[TIME](sec=ns // 10**9, nanosec=ns % 10**9)


def header(ns: int) -> Any:
    return T[HEADER](stamp=stamp(ns), frame_id='')


def joint_state(
    ns: int,
    names: list[str] | str,
    position: Sequence[float] = (),
    velocity: Sequence[float] = (),
    effort: Sequence[float] = (),
) -> Any:
    return T[JOINT_STATE](
        header=header(ns),
        name=list(names),
        position=np.array(position, dtype=np.float64),
        velocity=np.array(velocity, dtype=np.float64),
        effort=np.array(effort, dtype=np.float64),
    )


def wrench(ns: int, f: tuple[float, float, float]) -> Any:
    v3 = T['geometry_msgs/msg/Vector3']
    w = T['geometry_msgs/msg/Wrench'](force=v3(x=f[0], y=f[1], z=f[2]), torque=v3(x=0, y=0, z=0))
    return T[WRENCH_STAMPED](header=header(ns), wrench=w)


def ser(msg: Any) -> bytes:
    return bytes(TS.serialize_cdr(msg, msg.__msgtype__))


def write_test_bag(path: Path, n: int, flush_every: int | None = 100) -> BagWriter:
    """n samples at 1 ms on a state and a force topic, a /clock every 10; flushed every 100."""
    w = BagWriter(path)
    state = w.add_topic(STATE, JOINT_STATE, QOS)
    force = w.add_topic(FORCE, WRENCH_STAMPED, QOS)
    clock = w.add_topic(CLOCK_TOPIC, CLOCK, QOS)
    for k in range(n):
        ns = k * 1_000_000
        wall = WALL0 + 2_000_000 * k
        if k % 10 == 0:
            w.write(clock, ns, wall, ser(T[CLOCK](clock=stamp(ns))))
        w.write(state, ns, wall, ser(joint_state(ns, 'x', [k * 1e-6])))
        w.write(force, ns, wall, ser(wrench(ns, (k, -k, 0.5 * k))))
        if flush_every and (k + 1) % flush_every == 0:
            w.flush()
    return w


def test_bag_opens_in_rosbags_and_mcap_ros2_with_every_message(tmp_path: Path) -> None:
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    from rosbags.rosbag2 import Reader

    path = tmp_path / 'bag'
    write_test_bag(path, 1000).close()
    expected = {STATE: 1000, FORCE: 1000, CLOCK_TOPIC: 100}

    counts = Counter()
    with Reader(path) as reader:
        assert {c.topic: c.msgcount for c in reader.connections} == expected
        state = next(c for c in reader.connections if c.topic == STATE)
        assert state.ext.offered_qos_profiles[0].reliability.name == 'RELIABLE'
        assert reader.duration == 999_000_001  # log times are the stamps, 0 .. 999 ms
        for conn, timestamp, data in reader.messages():
            msg = TS.deserialize_cdr(data, conn.msgtype)
            counts[conn.topic] += 1
            if conn.topic == STATE:
                k = timestamp // 1_000_000
                assert msg.position[0] == k * 1e-6
    assert counts == expected

    counts = Counter()
    (mcap_file,) = path.glob('*.mcap')
    with open(mcap_file, 'rb') as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _schema, channel, message, decoded in reader.iter_decoded_messages():
            counts[channel.topic] += 1
            assert channel.metadata['topic_type_hash'].startswith('RIHS01_')
            assert yaml.safe_load(channel.metadata['offered_qos_profiles']) == QOS
            k = message.log_time // 1_000_000
            assert message.publish_time == WALL0 + 2_000_000 * k  # the wall time kept apart
            if channel.topic == FORCE:
                assert (decoded.wrench.force.x, decoded.wrench.force.y) == (k, -k)
    assert counts == expected

    meta = yaml.safe_load((path / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['version'] == 9 and meta['storage_identifier'] == 'mcap'
    assert meta['message_count'] == 2100
    assert {
        t['topic_metadata']['name']: t['message_count'] for t in meta['topics_with_message_count']
    } == expected


def test_metadata_is_written_at_once_and_refreshed_at_every_flush(tmp_path: Path) -> None:
    path = tmp_path / 'bag'
    w = write_test_bag(path, 250)
    meta = yaml.safe_load((path / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['message_count'] == 200 + 200 + 20  # the state of the last flush, k < 200
    w.close()
    meta = yaml.safe_load((path / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['message_count'] == 250 + 250 + 25


def snapshot_of_killed_recording(tmp_path: Path) -> tuple[Path, bytes]:
    """What SIGKILL leaves: 300 samples flushed, 50 more only in the writer's memory."""
    path = tmp_path / 'live'
    w = write_test_bag(path, 350)  # flushed after 100, 200, 300
    data = (path / w.file_name).read_bytes()
    killed = tmp_path / 'killed'
    killed.mkdir()
    (killed / 'metadata.yaml').write_text((path / 'metadata.yaml').read_text())
    (killed / w.file_name).write_bytes(data)
    return killed / w.file_name, data


def state_samples(bag: Bag) -> list[int]:
    return [lt // 1_000_000 for t, _, lt, _, _ in bag.read() if t == STATE]


def test_killed_recording_is_read_up_to_its_last_flush(tmp_path: Path) -> None:
    file, data = snapshot_of_killed_recording(tmp_path)
    bag = open_bag(file.parent)
    assert state_samples(bag) == list(range(300))
    assert bag.truncated == [file]
    # A kill in the middle of writing a chunk: whatever the cut, whole chunks only.
    last_chunk = data.rindex(b'\x06', 0, len(data) - 2000)  # somewhere in the last chunk
    cuts = range(max(9, last_chunk - 4000), len(data), 211)
    assert len(cuts) > 20
    for cut in cuts:
        file.write_bytes(data[:cut])
        samples = state_samples(open_bag(file.parent))
        assert samples == list(range(len(samples))), cut
        assert len(samples) % 100 == 0, cut


def test_recover_makes_a_killed_recording_readable_by_rosbags(tmp_path: Path) -> None:
    from rosbags.rosbag2 import Reader, ReaderError

    file, _ = snapshot_of_killed_recording(tmp_path)
    with pytest.raises(ReaderError, match='magic'):
        Reader(file.parent).open()  # no footer: rosbags refuses it as it is
    kept, files = recover(file.parent)
    assert (kept, files) == (300 + 300 + 30, 1)
    assert (file.parent / (file.name + '.truncated')).is_file()
    with Reader(file.parent) as reader:
        counts = Counter(c.topic for c, _, _ in reader.messages())
    assert counts == {STATE: 300, FORCE: 300, CLOCK_TOPIC: 30}
    assert recover(file.parent) == (630, 0)  # complete now: left alone


def test_a_type_missing_from_the_store_is_loaded_from_its_msg_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    prefix = tmp_path / 'prefix'
    (prefix / 'share/ament_index/resource_index/packages').mkdir(parents=True)
    (prefix / 'share/ament_index/resource_index/packages/probe_msgs').write_text('')
    (prefix / 'share/probe_msgs/msg').mkdir(parents=True)
    (prefix / 'share/probe_msgs/msg/Probe.msg').write_text(
        '# a probe\nstd_msgs/Header header\nfloat64 value\ngeometry_msgs/Vector3[] points\n'
    )
    monkeypatch.setenv('AMENT_PREFIX_PATH', str(prefix))
    msgtype = 'probe_msgs/msg/Probe'
    msgdef, rihs01 = message_definition(msgtype)
    assert msgdef.startswith('std_msgs/Header header') and 'MSG: geometry_msgs/Vector3' in msgdef
    assert rihs01.startswith('RIHS01_') and sim_stamped(msgtype)
    w = BagWriter(tmp_path / 'bag')
    topic = w.add_topic('/probe', msgtype, QOS)
    v3 = T['geometry_msgs/msg/Vector3']
    msg = TS.types[msgtype](header=header(5_000_000), value=2.5, points=[v3(x=1, y=2, z=3)])
    w.write(topic, 5_000_000, 5_000_000, ser(msg))
    w.close()
    ((_topic, _type, log_time, _pub, data),) = list(open_bag(tmp_path / 'bag').read())
    assert (log_time, decode(msgtype, data).value) == (5_000_000, 2.5)


def test_only_a_leading_header_or_clock_is_sim_time() -> None:
    assert sim_stamped(JOINT_STATE) and sim_stamped(CLOCK) and sim_stamped(WRENCH_STAMPED)
    assert not sim_stamped(STRING)
    assert not sim_stamped('rcl_interfaces/msg/Log')  # a wall-clock stamp
    assert not sim_stamped('no_such_msgs/msg/Nothing')


@pytest.mark.parametrize(
    ('frame_id', 'names', 'position', 'velocity', 'effort'),
    [
        ('', ['x'], [1.5], [], []),
        ('', ['y'], [], [], [0.25]),
        ('tool', ['x', 'y', 'z'], [1, 2, 3], [4, 5, 6], [7, 8, 9]),
        ('a', [], [], [], []),
        ('frame_7', ['joint_long_name', 'j'], [-1e-300], [math.inf], [math.nan]),
    ],
)
def test_joint_state_reader_equals_rosbags(
    frame_id: str,
    names: list[str],
    position: list[float],
    velocity: list[float],
    effort: list[float],
) -> None:
    # the first message of a shape is parsed field by field, the next one by its layout
    for k in (0, 1):
        msg = joint_state(
            123_456_789_012 + k * 10**9,
            names,
            [v * (k + 1) for v in position],
            [v * (k + 1) for v in velocity],
            [v * (k + 1) for v in effort],
        )
        msg.header.frame_id = frame_id
        data = ser(msg)
        fast = joint_state_cdr(data)
        ref = TS.deserialize_cdr(data, JOINT_STATE)
        assert (fast.header.stamp.sec, fast.header.stamp.nanosec) == (123 + k, 456_789_012)
        assert (fast.header.frame_id, fast.name) == (ref.header.frame_id, ref.name)
        for field in ('position', 'velocity', 'effort'):
            np.testing.assert_array_equal(getattr(fast, field), getattr(ref, field))
    big_endian = bytes(TS.serialize_cdr(msg, JOINT_STATE, little_endian=False))
    assert joint_state_cdr(big_endian) is None  # left to rosbags
    assert decode(JOINT_STATE, big_endian).name == names
    assert joint_state_cdr(data[:-9]) is None  # cut short: refused, not misread
    with pytest.raises(BagError, match=f'{len(data) - 9} bytes that are no {JOINT_STATE}: '):
        decode(JOINT_STATE, data[:-9])  # ... and by rosbags, in one line


# -- python -m mill_bag ---------------------------------------------------------------------


def mill_bag(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, '-m', 'mill_bag', *args], capture_output=True, text=True, timeout=120
    )


def test_recover_command_completes_a_killed_recording(tmp_path: Path) -> None:
    file, _ = snapshot_of_killed_recording(tmp_path)
    proc = mill_bag('recover', str(file.parent))
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == f'{file.parent}: recovered 630 messages in 1 file(s)\n'
    proc = mill_bag('recover', str(file.parent))
    assert (proc.returncode, proc.stdout) == (
        0,
        f'{file.parent}: complete already (630 messages)\n',
    )


@pytest.mark.parametrize(
    ('args', 'code', 'reason'),
    [
        (['recover', 'NO_SUCH_BAG'], 1, 'no such bag'),
        (['recover', 'JUNK'], 1, 'not an MCAP file'),
        (['repair', 'JUNK'], 2, "invalid choice: 'repair'"),
        (['recover'], 2, 'the following arguments are required: bag'),
    ],
)
def test_recover_command_errors_are_one_line(
    tmp_path: Path, args: list[str], code: int, reason: str
) -> None:
    junk = tmp_path / 'junk.mcap'
    junk.write_bytes(b'not an mcap file at all')
    names = {'NO_SUCH_BAG': str(tmp_path / 'no_such_bag'), 'JUNK': str(junk)}
    proc = mill_bag(*(names.get(a, a) for a in args))
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == code
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith('mill_bag: error: ') and reason in lines[0], lines[0]


def test_custom_data_is_in_every_metadata_and_survives_a_kill_and_recover(tmp_path: Path) -> None:
    notes = {'mill_record': 'axis', 'other': 'note'}
    path = tmp_path / 'live'
    w = BagWriter(path, custom_data=notes)
    state = w.add_topic(STATE, JOINT_STATE, QOS)
    w.write(state, 0, WALL0, ser(joint_state(0, 'x', [0.0])))
    w.flush()  # what a kill leaves: the metadata of the last flush
    killed = tmp_path / 'killed'
    killed.mkdir()
    (killed / 'metadata.yaml').write_text((path / 'metadata.yaml').read_text())
    (killed / w.file_name).write_bytes((path / w.file_name).read_bytes())
    w.close()
    meta = yaml.safe_load((path / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['custom_data'] == notes
    assert open_bag(path).custom_data == notes and open_bag(path).cut_short is None
    assert open_bag(killed).custom_data == notes
    assert recover(killed) == (1, 1)
    assert open_bag(killed).custom_data == notes
    assert open_bag(path / w.file_name).custom_data == {}  # a bare file has no metadata.yaml
