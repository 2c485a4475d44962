"""Hostile messages never end a recording (issue 25): what the recorder lets into a bag.

Streams generated with hypothesis mix good messages with negative, invalid and far-ahead
stamps, messages over the size limit and bytes that are no CDR, on stamped and unstamped
types. Checked against the rules of mill_bag.intake, written out again here: every good
message is in the bag that reads back, at the bag time it should have, and every bad one is
counted under its kind. First the checks alone (`Intake` + `BagWriter`, no ROS), then the
`TopicRecorder` of a real node fed the same way, on the topics a run records and on others.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mill_bag.intake import MAX_LEAD_NS, UNKNOWN_TYPE, Intake, Rejected
from mill_bag.reader import open_bag
from mill_bag.types import CLOCK, JOINT_STATE, STRING, typestore
from mill_bag.writer import RESERVE_NAME, BagWriter

TS = typestore()
T = TS.types
LIMIT = 2048  # max_bytes of these tests: a JointState of 250 positions is over it
WALL0 = 1_700_000_000_000_000_000
STATE, UNRELATED, CHATTER, CLOCK_TOPIC = '/robot/x/state', '/unrelated', '/chatter', '/clock'
TYPES = {STATE: JOINT_STATE, UNRELATED: JOINT_STATE, CHATTER: STRING, CLOCK_TOPIC: CLOCK}


@dataclass(frozen=True)
class Msg:
    topic: str
    data: bytes
    sec: int | None  # the stamp it carries (None: unstamped type, or no CDR)
    nanosec: int | None
    garbage: bool = False  # bytes that are no CDR message


def stamp(sec: int, nanosec: int) -> Any:
    return T['builtin_interfaces/msg/Time'](sec=sec, nanosec=nanosec)


def serialize(topic: str, sec: int, nanosec: int, size: int) -> bytes:
    msgtype = TYPES[topic]
    if msgtype == JOINT_STATE:
        header = T['std_msgs/msg/Header'](stamp=stamp(sec, nanosec), frame_id='')
        empty = np.zeros(0)
        msg = T[JOINT_STATE](
            header=header, name=['x'], position=np.ones(size), velocity=empty, effort=empty
        )
    elif msgtype == CLOCK:
        msg = T[CLOCK](clock=stamp(sec, nanosec))
    else:
        msg = T[STRING](data='s' * (8 * size))
    return bytes(TS.serialize_cdr(msg, msgtype))


secs = st.one_of(
    st.integers(0, 100),  # a sim graph's time
    st.integers(-(2**31), -1),  # negative
    st.integers(4000, 2**31 - 1),  # far ahead of the good ones
)
nanosecs = st.one_of(st.integers(0, 999_999_999), st.integers(10**9, 2**32 - 1))
sizes = st.one_of(st.integers(0, 8), st.integers(250, 400))  # the latter: too large
garbage = st.one_of(
    st.binary(max_size=11),  # no header, or too short for a stamp
    st.tuples(st.integers(1, 255), st.binary(max_size=40)).map(lambda t: bytes([t[0]]) + t[1]),
)


@st.composite
def message(draw: st.DrawFn) -> Msg:
    topic = draw(st.sampled_from(sorted(TYPES)))
    if draw(st.integers(0, 9)) == 0:
        return Msg(topic, draw(garbage), None, None, garbage=True)
    sec, nanosec = draw(secs), draw(nanosecs)
    data = serialize(topic, sec, nanosec, draw(sizes))
    if TYPES[topic] == STRING:
        return Msg(topic, data, None, None)
    return Msg(topic, data, sec, nanosec)


def expected(stream: list[Msg], sim_time: bool) -> tuple[list[tuple[int, int]], dict[str, int]]:
    """(index, bag time) of every message the rules of mill_bag.intake keep; drops per kind."""
    kept: list[tuple[int, int]] = []
    dropped: dict[str, int] = {}
    newest: int | None = None
    for i, m in enumerate(stream):
        received = WALL0 + i
        if len(m.data) > LIMIT:
            kind = 'too large'
        elif m.garbage and (len(m.data) < 4 or m.data[0] or m.data[1] > 1 or m.topic != CHATTER):
            kind = 'not CDR'  # (a String takes any CDR header: bytes after it are not read)
        elif m.sec is None:
            kept.append((i, (newest or 0) if sim_time else received))
            continue
        elif m.sec < 0:
            kind = 'negative stamp'
        elif m.nanosec is not None and m.nanosec >= 10**9:
            kind = 'invalid stamp'
        else:
            assert m.nanosec is not None
            ns = m.sec * 10**9 + m.nanosec
            if sim_time and newest is not None and ns > newest + MAX_LEAD_NS:
                kind = 'stamp ahead'
            else:
                if sim_time:
                    newest = ns if newest is None else max(newest, ns)
                kept.append((i, ns if sim_time else received))
                continue
        dropped[kind] = dropped.get(kind, 0) + 1
    return kept, dropped


def read_back(path: Path) -> list[tuple[str, int, bytes]]:
    return [(t, log, data) for t, _type, log, _pub, data in open_bag(path).read()]


_bags = itertools.count()


@pytest.mark.parametrize('sim_time', [True, False], ids=['sim_time', 'wall_time'])
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(stream=st.lists(message(), max_size=120), flush_every=st.integers(1, 50))
def test_the_checks_keep_every_good_message_and_count_every_bad_one(
    tmp_path_factory: pytest.TempPathFactory,
    sim_time: bool,
    stream: list[Msg],
    flush_every: int,
) -> None:
    path = tmp_path_factory.mktemp('intake') / f'bag{next(_bags)}'
    intake = Intake(sim_time, max_bytes=LIMIT)
    writer = BagWriter(path)
    infos = {t: writer.add_topic(t, msgtype, []) for t, msgtype in TYPES.items()}
    for i, m in enumerate(stream):
        received = WALL0 + i
        when = intake.log_time(m.data, TYPES[m.topic] != STRING, received)
        if isinstance(when, Rejected):
            intake.drop(m.topic, when, now=0.0)
        else:
            writer.write(infos[m.topic], when, received, m.data)
        if (i + 1) % flush_every == 0:
            writer.flush()
    writer.close()
    kept, dropped = expected(stream, sim_time)
    assert intake.counts == dropped
    assert read_back(path) == [(stream[i].topic, t, stream[i].data) for i, t in kept]


def test_each_kind_is_named_and_logged_once_a_second() -> None:
    intake = Intake(sim_time=True, max_bytes=LIMIT)
    good = serialize(STATE, 5, 0, 1)
    assert intake.log_time(good, True, WALL0) == 5 * 10**9
    assert intake.log_time(serialize(CHATTER, 0, 0, 1), False, WALL0) == 5 * 10**9
    cases = {
        'negative stamp': serialize(UNRELATED, -1, 0, 1),
        'invalid stamp': serialize(STATE, 1, 10**9, 1),
        'stamp ahead': serialize(CLOCK_TOPIC, 5 + 3601, 0, 0),
        'too large': serialize(STATE, 6, 0, 300),
        'not CDR': b'\x01\x00\x00\x00' + good[4:],
    }
    for kind, data in cases.items():
        rejected = intake.log_time(data, True, WALL0)
        assert isinstance(rejected, Rejected) and rejected.kind == kind, (kind, rejected)
        first = intake.drop(UNRELATED, rejected, now=10.0)
        assert first is not None and first.startswith(f'dropped a message on {UNRELATED}: {kind}')
        assert intake.drop(UNRELATED, rejected, now=10.9) is None  # within the second
        assert intake.drop(UNRELATED, rejected, now=11.0) == first.replace('1 so far', '3 so far')
    line = intake.drop('/odd', Rejected(UNKNOWN_TYPE, 'no message definition'), now=0.0)
    assert line == 'not recording /odd: unknown type (no message definition); 1 so far'
    assert intake.dropped == 5 * 3 + 1
    assert intake.describe().startswith('16 dropped (invalid stamp 3, negative stamp 3, ')


def test_the_writer_refuses_a_time_mcap_cannot_hold_and_stays_whole(tmp_path: Path) -> None:
    from mill_bag.errors import BagError

    writer = BagWriter(tmp_path / 'bag')
    info = writer.add_topic(STATE, JOINT_STATE, [])
    data = serialize(STATE, 1, 0, 1)
    writer.write(info, 1, WALL0, data)
    for log_time, publish_time in ((-1, WALL0), (1 << 64, WALL0), (2, -5)):
        with pytest.raises(BagError, match='is no MCAP time'):
            writer.write(info, log_time, publish_time, data)
    writer.write(info, 3, WALL0, data)
    writer.close()  # before issue 25: struct.error here too, the chunk held half a record
    assert [log for _t, log, _d in read_back(tmp_path / 'bag')] == [1, 3]
    assert not (tmp_path / 'bag' / RESERVE_NAME).exists()


def test_abort_ends_the_bag_at_its_last_flush_and_says_why(tmp_path: Path) -> None:
    writer = BagWriter(tmp_path / 'bag')
    info = writer.add_topic(STATE, JOINT_STATE, [])
    for k in range(5):
        writer.write(info, k, WALL0, serialize(STATE, k, 0, 1))
    writer.flush()
    writer.write(info, 5, WALL0, serialize(STATE, 5, 0, 1))  # not flushed: not in the file
    writer.abort('KeyError: 7')
    assert writer.closed and writer.message_count == 5
    bag = open_bag(tmp_path / 'bag')
    assert [log for _t, log, _d in read_back(tmp_path / 'bag')] == [0, 1, 2, 3, 4]
    assert bag.cut_short == 'KeyError: 7'
    assert not (tmp_path / 'bag' / RESERVE_NAME).exists()


# -- the recorder of a real node ------------------------------------------------------------


def generated_stream(count: int) -> list[Msg]:
    """`count` messages drawn by hypothesis (derandomized: the same list on every run)."""
    from hypothesis import Phase

    stream: list[Msg] = []

    @settings(
        max_examples=count,
        derandomize=True,
        database=None,
        deadline=None,
        phases=[Phase.generate],
        suppress_health_check=list(HealthCheck),
    )
    @given(message())
    def collect(m: Msg) -> None:
        stream.append(m)

    collect()
    return stream


def test_a_recorder_fed_a_hostile_stream_keeps_every_good_message(
    node_in, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from mill_bag.recorder import DROPPED, TopicRecorder
    from rclpy.qos import QoSProfile

    stream = generated_stream(600)
    kept, dropped = expected(stream, sim_time=True)
    assert set(dropped) == {
        'too large',
        'not CDR',
        'negative stamp',
        'invalid stamp',
        'stamp ahead',
    }
    node = node_in('/')
    # /robot/x/state stands for the topics of a run, the others for any other node's.
    rec = TopicRecorder(
        node, tmp_path / 'bag', sim_time=True, discover=False, max_message_bytes=LIMIT
    )
    taps = {topic: rec.tap(topic, msgtype) for topic, msgtype in TYPES.items()}
    # A topic of a type this machine has no definition of: not recorded, counted.
    with monkeypatch.context() as graph:
        graph.setattr(node, 'get_topic_names_and_types', lambda: [('/odd', ['no/msg/Such'])])
        publisher = SimpleNamespace(qos_profile=QoSProfile(depth=10))
        graph.setattr(node, 'get_publishers_info_by_topic', lambda _name: [publisher])
        rec.discover()
    for i, m in enumerate(stream):
        taps[m.topic](m.data)
        if i % 37 == 36:
            rec.flush()
    rec.close()
    assert rec.error is None
    assert read_back(tmp_path / 'bag') == [(stream[i].topic, t, stream[i].data) for i, t in kept]
    counts = {**dropped, UNKNOWN_TYPE: 1}
    assert rec.intake.counts == counts
    assert open_bag(tmp_path / 'bag').noted_counts(DROPPED) == counts
    described = rec.intake.describe()
    assert described.startswith(f'{sum(counts.values())} dropped (')
    assert rec.summary().endswith(f'; {described}')
    assert not (tmp_path / 'bag' / RESERVE_NAME).exists()


@pytest.mark.parametrize('broken', ['write', 'mcap'])
def test_an_unexpected_failure_closes_the_bag_and_says_so_in_one_line(
    node_in, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, broken: str
) -> None:
    """A bug, not bad input: the flush ends the recorder with one line and the bag closed
    (whole if the MCAP writer still works, else at its last flush)."""
    from mill_bag.recorder import TopicRecorder

    rec = TopicRecorder(node_in('/'), tmp_path / 'bag', sim_time=True, discover=False)
    tap = rec.tap(STATE, JOINT_STATE)
    for k in range(3):
        tap(serialize(STATE, k, 0, 1))
    rec.flush()
    tap(serialize(STATE, 3, 0, 1))

    def fail(*_args: object) -> None:
        raise KeyError(7)

    if broken == 'write':
        monkeypatch.setattr(rec.writer, 'write', fail)
    else:  # the MCAP writer itself: closing it fails too
        monkeypatch.setattr(rec.writer._mcap, 'add_message', fail)
        monkeypatch.setattr(rec.writer._mcap, 'finish', fail)
    rec._on_flush_timer()
    assert rec.error is not None and '\n' not in rec.error
    assert rec.error.startswith(f'cannot write the bag {tmp_path / "bag"} (KeyError: 7); closed it')
    assert rec.error.endswith('with 3 messages')
    assert rec.writer.closed and not (tmp_path / 'bag' / RESERVE_NAME).exists()
    bag = open_bag(tmp_path / 'bag')
    assert [log for _t, _type, log, _p, _d in bag.read()] == [0, 10**9, 2 * 10**9]
    assert bag.truncated == ([] if broken == 'write' else [bag.files[0]])
    rec.close()  # closed already: nothing more to say
