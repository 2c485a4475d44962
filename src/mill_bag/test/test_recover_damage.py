"""`recover` on a bag with flipped bytes (issue 25): it keeps every message of the intact
chunks, says in one line per damaged part what was lost, and never ends in a traceback.

The bags are real (BagWriter, zstd chunks with CRCs, message indexes), closed or left as a
killed recording leaves them (no summary, no footer). Bytes are flipped anywhere in one chunk
record, its frame included, at positions hypothesis draws and at a fixed set.
"""

from __future__ import annotations

import itertools
import shutil
import struct
import subprocess
import sys
from contextlib import nullcontext
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import example, given, settings
from hypothesis import strategies as st
from mill_bag.errors import BagError
from mill_bag.mcap_read import Damage
from mill_bag.reader import open_bag
from mill_bag.recover import DAMAGED, recover
from mill_bag.types import JOINT_STATE, typestore
from mill_bag.writer import BagWriter

TS = typestore()
CHUNKS, PER_CHUNK = 6, 40  # messages per chunk: 20 on each of two topics
TOPICS = ('/a/state', '/b/state')
Message = tuple[str, int, bytes]  # topic, log time, data


def joint_state(ns: int) -> bytes:
    t = TS.types
    header = t['std_msgs/msg/Header'](
        stamp=t['builtin_interfaces/msg/Time'](sec=ns // 10**9, nanosec=ns % 10**9), frame_id=''
    )
    empty = np.zeros(0)
    msg = t[JOINT_STATE](
        header=header, name=['x'], position=np.array([ns * 1e-9]), velocity=empty, effort=empty
    )
    return bytes(TS.serialize_cdr(msg, JOINT_STATE))


def write_bag(path: Path, killed: bool) -> list[list[Message]]:
    """CHUNKS chunks of PER_CHUNK messages, closed or as a SIGKILL after the last flush leaves
    it; the messages of each chunk."""
    live = path.with_name(path.name + '_live')
    w = BagWriter(live)
    infos = [w.add_topic(t, JOINT_STATE, []) for t in TOPICS]
    chunks: list[list[Message]] = []
    for c in range(CHUNKS):
        chunk = []
        for k in range(PER_CHUNK):
            ns = (c * PER_CHUNK + k) * 1_000_000
            info = infos[k % 2]
            data = joint_state(ns)
            w.write(info, ns, ns, data)
            chunk.append((info.name, ns, data))
        w.flush()
        chunks.append(chunk)
    if not killed:
        w.close()
    shutil.copytree(live, path)  # a killed recording: the file of the last flush
    (path / w.file_name).rename(path / f'{path.name}_0.mcap')
    meta = (path / 'metadata.yaml').read_text().replace(w.file_name, f'{path.name}_0.mcap')
    (path / 'metadata.yaml').write_text(meta)
    return chunks


def chunk_records(data: bytes) -> list[tuple[int, int]]:
    """(start, end) of every chunk record, walked by the MCAP framing."""
    out, pos = [], 8
    while pos + 9 <= len(data):
        op, length = struct.unpack_from('<BQ', data, pos)
        if op == 0x06:
            out.append((pos, pos + 9 + length))
        if op == 0x0F or pos + 9 + length > len(data):
            break
        pos += 9 + length
    return out


def messages(path: Path) -> list[Message]:
    return [(t, log, data) for t, _type, log, _pub, data in open_bag(path).read()]


_ORIGINALS: dict[bool, tuple[Path, list[list[Message]], bytes]] = {}
_copies = itertools.count()


def damaged_copy(
    tmp: Path, killed: bool, chunk: int, offset: int, xor: int
) -> tuple[Path, Path, list[list[Message]], tuple[int, int]]:
    """A copy of the bag (closed or killed) with byte `offset` of chunk record `chunk` flipped."""
    if killed not in _ORIGINALS:
        bag = tmp / f'original_{"killed" if killed else "closed"}'
        chunks = write_bag(bag, killed)
        _ORIGINALS[killed] = (bag, chunks, (bag / f'{bag.name}_0.mcap').read_bytes())
    original, chunks, data = _ORIGINALS[killed]
    records = chunk_records(data)
    assert len(records) == CHUNKS
    start, end = records[chunk]
    flipped = bytearray(data)
    flipped[start + offset % (end - start)] ^= xor
    bag = tmp / f'bag{next(_copies)}'
    shutil.copytree(original, bag)
    file = bag / f'{original.name}_0.mcap'
    file.write_bytes(bytes(flipped))
    return bag, file, chunks, (start, end)


@pytest.fixture(scope='module')
def tmp(tmp_path_factory: pytest.TempPathFactory) -> Path:
    _ORIGINALS.clear()
    return tmp_path_factory.mktemp('damage')


@settings(max_examples=150, deadline=None)
@given(
    killed=st.booleans(),
    chunk=st.integers(0, CHUNKS - 1),
    offset=st.one_of(st.integers(0, 60), st.integers(0, 10**6)),  # frame and header, anywhere
    xor=st.integers(1, 255),
)
# the low byte of the first chunk record's length: a damaged part of unknown size once
@example(killed=False, chunk=0, offset=1, xor=28)
@example(killed=True, chunk=0, offset=1, xor=28)
def test_recover_keeps_every_intact_chunk_and_counts_what_it_lost(
    tmp: Path, killed: bool, chunk: int, offset: int, xor: int
) -> None:
    bag, _file, chunks, (start, end) = damaged_copy(tmp, killed, chunk, offset, xor)
    damaged: list[Damage] = []
    kept, files = recover(bag, damaged)  # no exception, whatever the byte
    got = messages(bag)
    assert kept == len(got)
    intact = [m for i, c in enumerate(chunks) if i != chunk for m in c]
    assert [m for m in got if m not in chunks[chunk]] == intact  # all of them, in order
    assert got in (intact, [m for c in chunks for m in c])  # the damaged chunk: all or none
    lost = len(intact) + PER_CHUNK - len(got)
    assert sum(d.messages or 0 for d in damaged) == lost  # every count known, none invented
    assert all(d.messages is not None for d in damaged)
    for d in damaged:  # where: the flipped chunk
        first, last = (int(x) for x in d.where.split()[1].split('-'))
        assert start <= first < end and first < last
    if lost:
        ns = [m[1] for m in chunks[chunk]]
        assert [(d.first_ns, d.last_ns) for d in damaged if d.messages] == [(ns[0], ns[-1])]
        assert (
            open_bag(bag).custom_data[DAMAGED]
            == f'{len(damaged)} damaged part(s), 40 messages lost'
        )
    assert files == (1 if damaged or killed else 0)
    if files:  # complete now: rosbags reads it too
        from rosbags.rosbag2 import Reader

        with Reader(bag) as reader:
            assert sum(1 for _ in reader.messages()) == len(got)


def mill_bag(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, '-m', 'mill_bag', *args], capture_output=True, text=True, timeout=120
    )


@pytest.mark.parametrize('killed', [False, True], ids=['closed', 'killed'])
@pytest.mark.parametrize(
    ('offset', 'lost'),
    [
        (0, 0),  # the opcode: the chunk reads from its own fields
        (3, 0),  # its frame's length: likewise
        (40, 40),  # its CRC
        (61, 40),  # the zstd frame header
        (500, 40),  # compressed messages
    ],
)
def test_recover_command_says_what_each_damaged_part_lost(
    tmp: Path, killed: bool, offset: int, lost: int
) -> None:
    bag, file, chunks, (start, end) = damaged_copy(tmp, killed, 2, offset, 0x5A)
    with pytest.raises(BagError, match='damaged MCAP file') if lost else nullcontext():
        messages(bag)  # a reader refuses a bag that lost messages, in one line
    proc = mill_bag('recover', str(bag))
    assert 'Traceback' not in proc.stderr
    assert proc.returncode == (3 if lost else 0), proc.stderr
    (line,) = proc.stderr.splitlines()
    assert line.startswith(f'mill_bag: damaged: {file}: bytes {start}-')
    ns = [m[1] for m in chunks[2]]
    if lost:
        assert line.endswith(
            f'; {lost} messages lost, log times {ns[0] / 1e9:.9f} to {ns[-1] / 1e9:.9f} s'
        )
        assert f'bytes {start}-{end} (a chunk): ' in line
    else:  # read from the chunk's own fields, and rewritten with a sound frame
        assert f'bytes {start}-{end} (a chunk): its frame is damaged (opcode ' in line
        assert line.endswith('its fields are not; 0 messages lost')
    total = CHUNKS * PER_CHUNK - lost
    assert proc.stdout == (
        f'{bag}: recovered {total} messages in 1 file(s); 1 damaged part(s), {lost} messages lost\n'
    )
    assert len(messages(bag)) == total  # now it reads
    meta = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['message_count'] == total
    assert len(list(bag.glob('*.mcap.damaged'))) == 1  # the original is kept
