"""Bags without a ROS graph: the writer's bags open in rosbags and in mcap + mcap_ros2, a killed
recording loses only its unflushed tail and can be recovered, bags of another writer (rosbags,
MCAP and sqlite3) give the same RunRecord as the offline simulator, report metrics, bad input."""

from __future__ import annotations

import math
import subprocess
import sys
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
import yaml
from mill_bringup.bag import (
    CLOCK,
    DIAGNOSTIC_ARRAY,
    JOINT_STATE,
    JOINT_TRAJECTORY,
    WRENCH_STAMPED,
    BagWriter,
    open_bag,
    read_run,
    record_from_raw,
    record_topics,
    recover,
    typestore,
)
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.registry import job_for
from mill_bringup.metrics import SIGNALS, summarize
from mill_bringup.report import amplitude_at, amplitude_spectrum, max_window_rms
from mill_common.signals import AXES
from mill_trajectory.config import build_job

from mill_bringup import scenario
from mill_common import topics

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


def stamp(ns: int):
    return T['builtin_interfaces/msg/Time'](sec=ns // 10**9, nanosec=ns % 10**9)


def header(ns: int):
    return T['std_msgs/msg/Header'](stamp=stamp(ns), frame_id='')


def arr(values) -> np.ndarray:
    return np.array(values, dtype=np.float64)


def joint_state(ns, names, position=(), velocity=(), effort=()):
    return T[JOINT_STATE](
        header=header(ns),
        name=list(names),
        position=arr(position),
        velocity=arr(velocity),
        effort=arr(effort),
    )


def wrench(ns, f):
    v3 = T['geometry_msgs/msg/Vector3']
    w = T['geometry_msgs/msg/Wrench'](force=v3(x=f[0], y=f[1], z=f[2]), torque=v3(x=0, y=0, z=0))
    return T[WRENCH_STAMPED](header=header(ns), wrench=w)


def ser(msg) -> bytes:
    return bytes(TS.serialize_cdr(msg, msg.__msgtype__))


def write_test_bag(path: Path, n: int, flush_every: int | None = 100) -> BagWriter:
    """n samples at 1 ms on a state and a force topic, a /clock every 10; flushed every 100."""
    w = BagWriter(path)
    state = w.add_topic(topics.state('x'), JOINT_STATE, QOS)
    force = w.add_topic(topics.CUTTING_FORCE, WRENCH_STAMPED, QOS)
    clock = w.add_topic(topics.CLOCK, CLOCK, QOS)
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


def test_bag_opens_in_rosbags_and_mcap_ros2_with_every_message(tmp_path):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    from rosbags.rosbag2 import Reader

    path = tmp_path / 'bag'
    write_test_bag(path, 1000).close()
    expected = {topics.state('x'): 1000, topics.CUTTING_FORCE: 1000, topics.CLOCK: 100}

    counts = Counter()
    with Reader(path) as reader:
        assert {c.topic: c.msgcount for c in reader.connections} == expected
        state = next(c for c in reader.connections if c.topic == topics.state('x'))
        assert state.ext.offered_qos_profiles[0].reliability.name == 'RELIABLE'
        assert reader.duration == 999_000_001  # log times are the stamps, 0 .. 999 ms
        for conn, timestamp, data in reader.messages():
            msg = TS.deserialize_cdr(data, conn.msgtype)
            counts[conn.topic] += 1
            if conn.topic == topics.state('x'):
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
            if channel.topic == topics.CUTTING_FORCE:
                assert (decoded.wrench.force.x, decoded.wrench.force.y) == (k, -k)
    assert counts == expected

    meta = yaml.safe_load((path / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['version'] == 9 and meta['storage_identifier'] == 'mcap'
    assert meta['message_count'] == 2100
    assert {
        t['topic_metadata']['name']: t['message_count'] for t in meta['topics_with_message_count']
    } == expected


def test_metadata_is_written_at_once_and_refreshed_at_every_flush(tmp_path):
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


def state_samples(bag) -> list[int]:
    return [lt // 1_000_000 for t, _, lt, _, _ in bag.read() if t == topics.state('x')]


def test_killed_recording_is_read_up_to_its_last_flush(tmp_path):
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


def test_recover_makes_a_killed_recording_readable_by_rosbags(tmp_path):
    from rosbags.rosbag2 import Reader, ReaderError

    file, _ = snapshot_of_killed_recording(tmp_path)
    with pytest.raises(ReaderError, match='magic'):
        Reader(file.parent).open()  # no footer: rosbags refuses it as it is
    kept, files = recover(file.parent)
    assert (kept, files) == (300 + 300 + 30, 1)
    assert (file.parent / (file.name + '.truncated')).is_file()
    with Reader(file.parent) as reader:
        counts = Counter(c.topic for c, _, _ in reader.messages())
    assert counts == {topics.state('x'): 300, topics.CUTTING_FORCE: 300, topics.CLOCK: 30}
    assert recover(file.parent) == (630, 0)  # complete now: left alone


def test_a_type_missing_from_the_store_is_loaded_from_its_msg_file(tmp_path, monkeypatch):
    from mill_bringup.bag import decode, message_definition, sim_stamped

    prefix = tmp_path / 'prefix'
    (prefix / 'share/ament_index/resource_index/packages').mkdir(parents=True)
    (prefix / 'share/ament_index/resource_index/packages/mill_probe_msgs').write_text('')
    (prefix / 'share/mill_probe_msgs/msg').mkdir(parents=True)
    (prefix / 'share/mill_probe_msgs/msg/Probe.msg').write_text(
        '# a probe\nstd_msgs/Header header\nfloat64 value\ngeometry_msgs/Vector3[] points\n'
    )
    monkeypatch.setenv('AMENT_PREFIX_PATH', str(prefix))
    msgtype = 'mill_probe_msgs/msg/Probe'
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


# -- a bag written by another writer --------------------------------------------------------


def foreign_bag(tmp_path: Path, storage: str, feed: bool = False):
    """The offline simulation of 0.4 s of the job, written by rosbags' Writer as a recorder
    on wall time would (log time = receive time), with the contract's topics and types."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    scen = scenario.load('slotting')
    scen.add_override('trajectory.duration=0.4')
    rec = simulate(job_for(scen))
    job = build_job(scen.parameters('trajectory'))
    n = rec.t.size
    dt_ns = 1_000_000
    s = rec.signals
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    path = tmp_path / f'foreign_{storage}'
    with Writer(path, version=9, storage_plugin=plugin) as w:
        conns = {}

        def put(topic, msgtype, k, msg):
            if topic not in conns:
                conns[topic] = w.add_connection(topic, msgtype, typestore=TS)
            w.write(conns[topic], WALL0 + k * 3_100_000 + len(conns), ser(msg))

        status = T['diagnostic_msgs/msg/DiagnosticStatus']
        kv = T['diagnostic_msgs/msg/KeyValue']
        for k in range(n):
            ns = k * dt_ns
            for i, axis in enumerate('xyz'):
                put(
                    topics.state(axis), JOINT_STATE, k, joint_state(ns, axis, [s['position'][k, i]])
                )
                put(
                    topics.estimate(axis),
                    JOINT_STATE,
                    k,
                    joint_state(
                        ns,
                        axis,
                        [0.0],
                        [s['estimate_velocity'][k, i]],
                        [s['estimate_disturbance'][k, i]],
                    ),
                )
                put(
                    topics.joint_command(axis),
                    JOINT_STATE,
                    k,
                    joint_state(ns, axis, effort=[s['torque'][k, i]]),
                )
            truth = joint_state(
                ns, 'xyz', [0, 0, 0], s['true_velocity'][k], s['true_disturbance'][k]
            )
            put(topics.GROUND_TRUTH, JOINT_STATE, k, truth)
            put(topics.CUTTING_FORCE, WRENCH_STAMPED, k, wrench(ns, s['force'][k]))
            if k % 10 == 0:
                points = []
                for j in range(10):
                    kk = min(k + j, n - 1)
                    points.append(
                        T['trajectory_msgs/msg/JointTrajectoryPoint'](
                            positions=arr(s['reference'][kk]),
                            velocities=arr(s['reference_velocity'][kk]),
                            accelerations=arr([0, 0, 0]),
                            effort=arr([]),
                            time_from_start=T['builtin_interfaces/msg/Duration'](
                                sec=0, nanosec=j * dt_ns
                            ),
                        )
                    )
                put(
                    topics.REFERENCE,
                    JOINT_TRAJECTORY,
                    k,
                    T[JOINT_TRAJECTORY](header=header(ns), joint_names=list('xyz'), points=points),
                )
            if k % 100 == 0:
                diag = T[DIAGNOSTIC_ARRAY](
                    header=header(ns),
                    status=[
                        status(
                            level=0,
                            name='mill_trajectory: job',
                            message='job running',
                            hardware_id='mill',
                            values=[
                                kv(key='state', value='running'),
                                kv(key='end_time', value=repr(job.end_time)),
                            ],
                        )
                    ],
                )
                put(topics.DIAGNOSTICS, DIAGNOSTIC_ARRAY, k, diag)
                if feed:  # a feed override (issue 4) as std_msgs/Float64, 1.0 -> 0.8
                    value = 1.0 - 0.2 * k / n
                    put(
                        topics.FEED_OVERRIDE,
                        'std_msgs/msg/Float64',
                        k,
                        T['std_msgs/msg/Float64'](data=value),
                    )
    return path, rec


@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_a_bag_of_another_writer_gives_the_offline_record(tmp_path, storage):
    path, rec = foreign_bag(tmp_path, storage)
    run = read_run(path)
    assert (run.n, run.dt_ns, run.axes) == (rec.t.size, 1_000_000, ['x', 'y', 'z'])
    assert run.missing == {}
    np.testing.assert_array_equal(run.record.t, rec.t)
    for name in SIGNALS:
        np.testing.assert_array_equal(run.record[name], rec[name], err_msg=name)
    assert summarize(run.record, 0.1) == summarize(rec, 0.1)
    assert run.feed_override is None
    if storage == 'mcap':  # rosbags writes publish time = log time = the receive time
        assert run.state_wall_ns is not None and run.state_wall_ns[1] - run.state_wall_ns[0] > 0


def test_record_built_in_two_processes_equals_one(tmp_path):
    path, _ = foreign_bag(tmp_path, 'mcap')
    raw: dict[str, list[bytes]] = {}
    for topic, _type, _log, _pub, data in open_bag(path).read():
        raw.setdefault(topic, []).append(data)
    types = record_topics(AXES)
    raw = {t: raw[t] for t in types}
    one, missing_one = record_from_raw(raw, types, AXES, 401, 1_000_000, workers=1)
    two, missing_two = record_from_raw(raw, types, AXES, 401, 1_000_000, workers=2)
    assert missing_one == missing_two == dict.fromkeys(missing_one, 0)
    assert len(missing_one) == 3 * 3 + 2  # every listened per-sample topic
    for name in SIGNALS:
        np.testing.assert_array_equal(one[name], two[name], err_msg=name)
        assert np.isfinite(one[name]).any(), name


def test_feed_override_is_reported_when_the_bag_has_it(tmp_path):
    from mill_bringup.report import analyse, feed_text

    path, _ = foreign_bag(tmp_path, 'mcap', feed=True)
    run = read_run(path)
    values = [v for _, v in run.feed_override]
    assert values == [1.0 - 0.2 * k / run.n for k in range(0, run.n, 100)]
    text = feed_text(analyse(run, 'f', 0.1, 0.1, [60.0]))
    assert text == (
        f'feed override: {len(values)} messages, min {min(values):.3f}, '
        f'mean {sum(values) / len(values):.3f}, max 1.000'
    )


def test_report_command_writes_markdown_and_plots(tmp_path):
    path, _ = foreign_bag(tmp_path, 'mcap')
    out = tmp_path / 'report'
    proc = subprocess.run(
        [
            sys.executable,
            '-m',
            'mill_bringup.report',
            str(path),
            '--out',
            str(out),
            '--skip',
            '0.1',
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert 'no feed override in this bag' in proc.stdout
    text = (out / 'report.md').read_text()
    pngs = sorted(p.name for p in out.glob('*.png'))
    assert pngs == sorted(
        [
            'position.png',
            'tracking_error.png',
            'torque.png',
            'disturbance.png',
            'disturbance_zoom.png',
            'cutting_force.png',
            'contour.png',
            'error_spectrum.png',
            'loop_timing.png',
        ]
    )
    for name in pngs:
        assert (out / name).stat().st_size > 10_000, name
        assert f']({name})' in text


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
def test_joint_state_reader_equals_rosbags(frame_id, names, position, velocity, effort):
    from mill_bringup.bag import decode, joint_state_cdr

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


# -- report metrics -------------------------------------------------------------------------


def test_amplitude_at_reads_tones_between_bins_and_the_spectrum_on_a_bin():
    dt = 1e-3
    t = np.arange(52_333) * dt
    x = 4e-6 * np.sin(2 * np.pi * 60 * t + 0.3) + 1e-6 * np.sin(2 * np.pi * 120 * t) + 2e-6
    assert amplitude_at(x, dt, 60.0) == pytest.approx(4e-6, rel=1e-3)
    assert amplitude_at(x, dt, 120.0) == pytest.approx(1e-6, rel=1e-3)
    assert amplitude_at(x, dt, 90.0) < 1e-9
    n = 50_000  # 60 Hz on bin 3000
    f, amp = amplitude_spectrum(x[:n], dt)
    assert f[3000] == pytest.approx(60.0)
    assert amp[3000] == pytest.approx(4e-6, rel=1e-3)


def test_max_window_rms_finds_the_burst_and_skips_gaps():
    x = np.zeros(10_000)
    x[5000:5100] = 3.0  # a 0.1 s burst at 1 kHz
    assert max_window_rms(x, 100) == pytest.approx(3.0)
    assert max_window_rms(x, 200) == pytest.approx(3.0 / math.sqrt(2))
    x[5050] = np.nan  # no full window covers the burst now
    assert max_window_rms(x, 100) == pytest.approx(3.0 * math.sqrt(50 / 100))


# -- bad input ------------------------------------------------------------------------------


def bad_inputs(tmp_path: Path) -> dict[str, tuple[list[str], str]]:
    empty_dir = tmp_path / 'empty_dir'
    empty_dir.mkdir()
    BagWriter(tmp_path / 'empty_bag').close()
    w = BagWriter(tmp_path / 'other_topics')
    chatter = w.add_topic('/chatter', 'std_msgs/msg/String', QOS)
    for i in range(10):
        w.write(chatter, i, i, ser(T['std_msgs/msg/String'](data=f'hello {i}')))
    w.close()
    (tmp_path / 'junk.mcap').write_bytes(b'not an mcap file at all')
    broken = tmp_path / 'broken_meta'
    broken.mkdir()
    (broken / 'metadata.yaml').write_text('rosbag2_bagfile_information: [unclosed')
    return {
        'missing': ([str(tmp_path / 'no_such_bag')], 'no such bag'),
        'empty directory': ([str(empty_dir)], 'no metadata.yaml and no .mcap file'),
        'empty bag': ([str(tmp_path / 'empty_bag')], 'holds no messages'),
        'no mill topics': ([str(tmp_path / 'other_topics')], 'no /mill/<axis>/state topic'),
        'not mcap': ([str(tmp_path / 'junk.mcap')], 'not an MCAP file'),
        'broken metadata': ([str(broken)], 'not a rosbag2 metadata file'),
        'bad freqs': ([str(tmp_path / 'empty_bag'), '--freqs', '60,abc'], 'not a list of numbers'),
        'bad window': ([str(tmp_path / 'empty_bag'), '--window', '-1'], 'must be > 0'),
    }


BAD = [
    'missing',
    'empty directory',
    'empty bag',
    'no mill topics',
    'not mcap',
    'broken metadata',
    'bad freqs',
    'bad window',
]


@pytest.mark.parametrize('case', BAD)
def test_bad_input_gives_one_line_error(tmp_path, case):
    args, reason = bad_inputs(tmp_path)[case]
    proc = subprocess.run(
        [sys.executable, '-m', 'mill_bringup.report', *args, '--out', str(tmp_path / 'out')],
        capture_output=True,
        text=True,
        timeout=120,
    )
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode != 0
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith('report: error: ') and reason in lines[0], lines[0]
    assert not (tmp_path / 'out' / 'report.md').exists()
