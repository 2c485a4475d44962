"""Recording on a full disk, for real: each test mounts a small tmpfs and fills it.

- The bag writer: a write the OS refuses cuts the bag short at its last complete flush;
  metadata.yaml says so, no temporary file is left, `report` names the cause, and
  `recover` completes the bag once there is room.
- `python -m mill_bag recover` on a full disk: one line, exit 1, the bag unchanged.
- The `recorder` node on a full disk: one line, exit 1, the bag readable and marked.

Mounting needs root (CAP_SYS_ADMIN); without it the tests are skipped and say why.
"""

from __future__ import annotations

import hashlib
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
import yaml
from mill_analysis.bag_run import read_run
from mill_bag.errors import BagError
from mill_bag.reader import open_bag
from mill_bag.recover import recover
from mill_bag.types import JOINT_STATE
from mill_bag.writer import RESERVE_NAME, BagCutShort, BagWriter

from mill_common import topics
from test.test_recording import FakePlant, both_readers, ros_node

T_NS = 1_000_000
# The absolute name a node in the root namespace records the x state under.
STATE_X = topics.qualify(topics.state('x'))
FULL = 'no space left on device'


@pytest.fixture
def small_disk(tmp_path: Path) -> Iterator[Callable[[str], Path]]:
    """small_disk('1m') -> a fresh tmpfs of that size, unmounted after the test."""
    mounted: list[Path] = []

    def mount(size: str) -> Path:
        where = tmp_path / f'disk{len(mounted)}'
        where.mkdir()
        try:
            done = subprocess.run(
                ['mount', '-t', 'tmpfs', '-o', f'size={size}', 'tmpfs', str(where)],
                capture_output=True,
                text=True,
                timeout=30,
            )
        except FileNotFoundError:
            pytest.skip('no mount command: cannot make a small disk to fill')
        if done.returncode != 0:
            reason = done.stderr.strip() or f'exit code {done.returncode}'
            pytest.skip(f'cannot mount a tmpfs to fill (needs root): {reason}')
        mounted.append(where)
        return where

    yield mount
    for where in reversed(mounted):
        if subprocess.run(['umount', str(where)], capture_output=True).returncode != 0:
            subprocess.run(['umount', '-l', str(where)], capture_output=True)


def resize(where: Path, size: str) -> None:
    subprocess.run(['mount', '-o', f'remount,size={size}', str(where)], check=True, timeout=30)


def state_cdr(k: int) -> bytes:
    """A JointState of sample k (position k µm, stamp k T), serialized (CDR)."""
    import numpy as np
    from mill_bag.types import typestore

    store = typestore()
    t = store.types
    stamp = t['builtin_interfaces/msg/Time'](sec=k * T_NS // 10**9, nanosec=k * T_NS % 10**9)
    msg = t[JOINT_STATE](
        header=t['std_msgs/msg/Header'](stamp=stamp, frame_id='plant'),
        name=['x'],
        position=np.array([k * 1e-6]),
        velocity=np.array([0.0]),
        effort=np.array([], dtype=np.float64),
    )
    return bytes(store.serialize_cdr(msg, JOINT_STATE))


def fill_until_cut(bag: Path, flush_every: int = 100) -> tuple[BagCutShort, int, int]:
    """Write state messages into a new bag, flushing every `flush_every`, until the disk is
    full: (the error, messages written, messages in the last complete flush)."""
    writer = BagWriter(bag, compression='none')
    topic = writer.add_topic(STATE_X, JOINT_STATE, [])
    flushed = 0
    for k in range(10**6):
        writer.write(topic, k * T_NS, k * T_NS, state_cdr(k))
        if (k + 1) % flush_every == 0:
            try:
                writer.flush()
            except BagCutShort as exc:
                assert writer.cut_short == FULL and writer.closed
                return exc, k + 1, flushed
            flushed = k + 1
    raise AssertionError('the disk never filled')


def digest(directory: Path) -> dict[str, str]:
    return {
        p.name: hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(directory.iterdir())
        if p.is_file()
    }


def test_a_full_disk_cuts_the_bag_short_at_its_last_flush(small_disk) -> None:
    disk = small_disk('1m')
    bag = disk / 'bag'
    error, written, flushed = fill_until_cut(bag)
    assert str(error) == (
        f'{FULL}: the bag {bag} is cut short after {flushed} messages '
        f'(`python -m mill_bag recover {bag}` completes it once there is room)'
    )
    # The full disk's whole room went to the bag: 1 MiB of about 110-byte records.
    assert 5000 < flushed < written
    assert sorted(p.name for p in bag.iterdir()) == ['bag_0.mcap', 'metadata.yaml']
    meta = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['custom_data'] == {'cut_short': FULL}
    assert meta['message_count'] == flushed

    # Read as it is: every message of the complete flushes, in order, and the cause named.
    reader = open_bag(bag)
    rows = list(reader.read())
    assert reader.cut_short == FULL and reader.truncated == [bag / 'bag_0.mcap']
    assert [log // T_NS for _t, _ty, log, _p, _d in rows] == list(range(flushed))
    run = read_run(bag)
    assert run.n == flushed
    assert any(f'cut short ({FULL})' in note for note in run.notes), run.notes
    assert not any('killed' in note for note in run.notes)

    # recover needs room for the complete copy: refused on the full disk, done after.
    before = digest(bag)
    with pytest.raises(BagError, match=f'cannot recover {bag}: {FULL}'):
        recover(bag)
    assert digest(bag) == before
    resize(disk, '4m')
    assert recover(bag) == (flushed, 1)
    by_rosbags, by_mcap, _ = both_readers(bag)
    assert by_rosbags == by_mcap == {STATE_X: flushed}
    meta = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['custom_data'] == {'cut_short': FULL}  # still cut short in time
    assert not (bag / RESERVE_NAME).exists()


def test_recover_on_a_full_disk_gives_one_line_and_leaves_no_stub(small_disk, tmp_path):
    # A killed recording (flushed, never closed), moved onto a disk with too little room.
    source = tmp_path / 'killed'
    writer = BagWriter(source, compression='none')
    topic = writer.add_topic(STATE_X, JOINT_STATE, [])
    for k in range(3000):
        writer.write(topic, k * T_NS, k * T_NS, state_cdr(k))
    writer.flush()  # on disk; no close(): what a SIGKILL leaves
    size = (source / 'killed_0.mcap').stat().st_size
    disk = small_disk('1m')
    bag = disk / 'killed'
    bag.mkdir()
    for f in source.iterdir():
        (bag / f.name).write_bytes(f.read_bytes())
    # Leave one page: the copy needs more (its message index alone is 16 bytes a message).
    free = subprocess.run(['df', '--output=avail', '-B1', str(disk)], capture_output=True)
    avail = int(free.stdout.split()[-1])
    (disk / 'ballast').write_bytes(bytes(max(0, avail - 4096)))
    assert size > 3000 * 16
    before = digest(bag)

    done = subprocess.run(
        [sys.executable, '-m', 'mill_bag', 'recover', str(bag)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert done.returncode == 1, done.stderr
    assert len(lines) == 1 and lines[0].startswith(
        f'mill_bag: error: cannot recover {bag}: {FULL} (the complete copy needs about '
    ), done.stderr
    assert lines[0].endswith('; the bag is unchanged')
    assert digest(bag) == before  # no stub, nothing renamed, metadata as it was


@pytest.mark.system
def test_the_recorder_on_a_full_disk_ends_with_one_line(start_node, small_disk):
    disk = small_disk('1m')
    bag = disk / 'bag'
    recorder = start_node(
        'mill_bag.recorder',
        'recorder',
        *('-p', f'output:={bag}', '-p', 'compression:=none', '-p', 'use_sim_time:=true'),
        *('-p', f'topics:={[topics.state("x"), topics.CUTTING_FORCE]}'),
        params_file=False,
    )
    with ros_node('fake_plant') as (node, _executor):
        plant = FakePlant(node)
        deadline = time.monotonic() + 120
        k = 0
        while not plant.matched():
            assert time.monotonic() < deadline, 'the recorder never subscribed'
            time.sleep(0.05)
        while recorder.alive():  # about 200 kB/s: 1 MiB fills within seconds
            assert time.monotonic() < deadline, 'the recorder never hit the full disk'
            plant.publish(k)
            k += 1
            time.sleep(0.001)
    code, _out, err = recorder.wait(timeout=30)
    assert code == 1, err
    assert 'Traceback' not in err
    ours = [line for line in err.splitlines() if line.startswith('recorder:')]
    assert len(ours) == 1, err
    assert ours[0].startswith(f'recorder: error: {FULL}: the bag {bag} is cut short after ')
    others = [line for line in err.splitlines() if line.strip() and line not in ours]
    assert all(line.startswith('[INFO]') for line in others), err  # the start-up log line

    assert sorted(p.name for p in bag.iterdir()) == ['bag_0.mcap', 'metadata.yaml']
    reader = open_bag(bag)
    rows = list(reader.read())
    assert reader.cut_short == FULL
    states = [log // T_NS for t, _ty, log, _p, _d in rows if t == STATE_X]
    assert states == list(range(len(states))) and len(states) > 1000
    run = read_run(bag)
    assert any(f'cut short ({FULL})' in note for note in run.notes), run.notes
