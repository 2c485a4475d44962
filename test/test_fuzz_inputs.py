"""Every node survives a stream of malformed and foreign messages, and the job's record is the
offline run's.

A lockstep slotting job runs (`run_scenario slotting --duration 2 --compare-offline`) while
this test publishes, from a node of its own, a stream of JointState and JointTrajectory
messages generated with hypothesis on every state, command, estimate, observer state,
reference and feed-override topic: unknown and missing joints, arrays shorter than the joint
list or empty, NaN and ±inf, stamps off the grid, repeated, in the past, negative or far
ahead, and senders that are not the topic's owner.

Who sends a message is its publisher as the graph names it (its GID; docs/reliability.md,
"Threat model"): every message of this test's node is foreign, whatever its frame_id. The
generator still keeps to the older rule, where a frame_id claim decided: most messages carry another
name and may hold anything; those that carry the owner's name are malformed: their stamp
names no sample the owner has not sent already (repeated, in the past, off the grid,
negative, far ahead), or, stamped with the next sample, their content is what every reader
drops (a command's NaN is not among those: it is the controller's brake request).

The run is recorded (`--record`), and the JointStates of the stream also go to a topic no
node reads (UNRELATED), as any node of the domain may publish anything (issue 25).

Checked: every node lives to the end of the job; the runner ends with exit code 1 only
because foreign messages were seen, and says so; no sample is missing and the record (the
foreign and malformed messages left out) equals the offline run exactly; the nodes counted
drops on /diagnostics. The recorder kept running and closed a complete bag: it holds every
message of UNRELATED with a sane stamp and counts those with a negative one. The stream is
generated once, derandomized (the same every run); hypothesis does not shrink it (that would
rerun the graph).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time
from dataclasses import dataclass

import pytest
from builtin_interfaces.msg import Duration, Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st
from mill_bag.cdr import cdr_stamp_ns
from mill_bag.reader import open_bag
from mill_bag.recorder import DROPPED
from mill_bag.writer import RESERVE_NAME
from mill_common.ros import DATA_QOS, from_stamp
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from mill_common import topics
from test.conftest import ros_node

T_NS = 1_000_000  # sample_period of config/slotting.yaml
AXES = ('x', 'y', 'z')
MESSAGES = 400  # generated messages, published in turn until the job ends
PERIOD = 0.004  # [s] of wall time between two published messages
# How far behind the newest /clock tick c a stamp must be for every reader (and the runner's
# monitor) to have the owner's message of it already: the plant publishes tick c after all
# commands of c - 1, so every node has step c - 2; 5 leaves room. A reference: the
# controllers had the point of c - 1, sent with the tick 20 samples before it at the latest
# (preview_time 20 ms, clock_period 10 ms in the scenario), and the trajectory's messages
# arrive in order.
MARGIN = 5
REFERENCE_MARGIN = 30
TICK = 10  # samples between /clock ticks (clock_period 10 ms)
UNRELATED = '/fuzz/unrelated'  # recorded (the run records the domain), read by no node
FAR = 30_000_000_000  # [ns] a far stamp: later than any reference may lead (20 s), and the job
# A far-ahead sample of the other topics: 0.3 s to 2 s ahead (the attack of issue 25), later
# than the plant can be and within the job, so its owner's message of it comes later: the
# record, like the nodes, must not take the spoof first.
AHEAD = 300

# topic -> (owner named in header.frame_id, fields its readers need of the axis's joint)
JOINT_STATE_TOPICS: dict[str, tuple[str, tuple[str, ...]]] = {}
for _a in AXES:
    JOINT_STATE_TOPICS[topics.state(_a)] = ('plant', ('position',))
    JOINT_STATE_TOPICS[topics.joint_command(_a)] = (f'{_a}_controller', ('effort',))
    JOINT_STATE_TOPICS[topics.estimate(_a)] = (f'{_a}_observer', ('position', 'velocity', 'effort'))
    JOINT_STATE_TOPICS[topics.observer_state(_a)] = ('', ())  # foreign senders only
JOINT_STATE_TOPICS[topics.FEED_OVERRIDE] = ('', ())  # nobody listens in this scenario
OWNERS = {t: o for t, (o, _) in JOINT_STATE_TOPICS.items()} | {topics.REFERENCE: 'trajectory'}
STAMPS = ('next', 'repeat', 'past', 'off_grid', 'negative', 'far_ahead')
FIELDS = ('position', 'velocity', 'effort')


@dataclass(frozen=True)
class Fuzz:
    """One message to publish; its stamp is resolved against the job's clock when sent."""

    topic: str
    sender: str | None  # None: the topic's owner
    stamp: str  # one of STAMPS
    amount: int  # steps back (past), ns off the grid, samples further ahead (far_ahead)
    names: tuple[str, ...] = ()
    arrays: tuple[tuple[float, ...], ...] = ((), (), ())  # position, velocity, effort
    points: tuple[tuple[int, tuple[float, ...], tuple[float, ...], tuple[float, ...]], ...] = ()


text = st.text(st.characters(exclude_categories=('Cs',), exclude_characters='\x00'), max_size=8)
any_float = st.floats(allow_nan=True, allow_infinity=True)
finite = st.floats(-1.0, 1.0)
non_finite = st.sampled_from([math.nan, math.inf, -math.inf])
any_values = st.lists(any_float, max_size=4).map(tuple)
any_names = st.lists(st.sampled_from(['x', 'y', 'z', 'w', '', 'X']) | text, max_size=4).map(tuple)
foreign_sender = st.sampled_from(
    ['', 'intruder', 'x_controller', 'y_observer', 'plant', 'trajectory', 'mill_monitor']
) | text.filter(bool)


@st.composite
def joint_state(draw: st.DrawFn, topic: str) -> Fuzz:
    owner, needed = JOINT_STATE_TOPICS[topic]
    stamp, amount = draw(st.sampled_from(STAMPS)), draw(st.integers(1, 10**6))
    if not owner or draw(st.integers(0, 3)):  # three in four: another sender, any content
        arrays = tuple(draw(any_values) for _ in FIELDS)
        return Fuzz(topic, draw(foreign_sender), stamp, amount, draw(any_names), arrays)
    axis = topic.split('/')[2]
    kinds = ['unknown_joint', 'short', 'non_finite']
    if stamp != 'next':
        kinds.append('valid')  # stamped with a sample the owner has sent already
    elif needed == ('effort',):
        kinds.remove('non_finite')  # the controller's brake request, not malformed
    kind = draw(st.sampled_from(kinds))
    others = st.sampled_from([a for a in ['x', 'y', 'z', 'w', ''] if a != axis])
    if kind == 'unknown_joint':
        names = tuple(draw(st.lists(others, max_size=3)))
        arrays = tuple(draw(any_values) for _ in FIELDS)
    elif kind == 'short':
        names = (*draw(st.lists(others, max_size=2)), axis)
        cut = draw(st.sampled_from(needed))
        arrays = tuple(
            tuple(draw(st.lists(finite, max_size=len(names) - 1 if f == cut else 4)))
            for f in FIELDS
        )
    else:
        names = (axis,)
        bad = draw(st.sampled_from(needed)) if kind == 'non_finite' else None
        arrays = tuple((draw(non_finite if f == bad else finite),) for f in FIELDS)
    return Fuzz(topic, None, stamp, amount, names, arrays)


@st.composite
def reference(draw: st.DrawFn) -> Fuzz:
    stamp, amount = draw(st.sampled_from(STAMPS)), draw(st.integers(1, 10**6))
    if draw(st.integers(0, 3)):  # another sender, any content
        offsets = st.integers(-2 * T_NS, 50 * T_NS)
        point = st.tuples(offsets, any_values, any_values, any_values)
        points = tuple(draw(st.lists(point, max_size=3)))
        return Fuzz(
            topics.REFERENCE, draw(foreign_sender), stamp, amount, draw(any_names), (), points
        )
    kinds = ['no_joints', 'short', 'non_finite', 'point_off_grid', 'empty']
    if stamp != 'next':
        kinds.append('valid')
    kind = draw(st.sampled_from(kinds))
    names = () if kind == 'no_joints' else AXES
    size = draw(st.integers(0, 2)) if kind == 'short' else 3
    points = []
    for i in range(0 if kind == 'empty' else draw(st.integers(1, 40))):
        offset = i * T_NS + (draw(st.integers(1, T_NS - 1)) if kind == 'point_off_grid' else 0)
        value = non_finite if kind == 'non_finite' else finite
        positions = tuple(draw(value) for _ in range(size))
        points.append((offset, positions, tuple(draw(finite) for _ in AXES), ()))
    return Fuzz(topics.REFERENCE, None, stamp, amount, names, (), tuple(points))


def generated_stream(count: int) -> list[Fuzz]:
    """`count` messages drawn by hypothesis (derandomized: the same list on every run)."""
    stream: list[Fuzz] = []
    strategy = st.sampled_from([*JOINT_STATE_TOPICS, topics.REFERENCE]).flatmap(
        lambda t: reference() if t == topics.REFERENCE else joint_state(t)
    )

    @settings(
        max_examples=count,
        derandomize=True,
        database=None,
        deadline=None,
        phases=[Phase.generate],
        suppress_health_check=list(HealthCheck),
    )
    @given(strategy)
    def collect(fuzz: Fuzz) -> None:
        stream.append(fuzz)

    collect()
    return stream


def stamp_of(fuzz: Fuzz, c: int) -> int:
    """The stamp [ns] of a message sent while the newest /clock tick is c (samples)."""
    if fuzz.topic == topics.REFERENCE:
        base = max(c - REFERENCE_MARGIN, 0) // TICK * TICK
    else:
        base = max(c - MARGIN, 0)
    if fuzz.stamp == 'next':
        return (c + 1) * T_NS
    if fuzz.stamp == 'repeat':
        return base * T_NS
    if fuzz.stamp == 'past':
        return (base - 1 - fuzz.amount % 1000) * T_NS  # negative near the start: still bad
    if fuzz.stamp == 'off_grid':
        return (base + fuzz.amount % 20) * T_NS + 1 + fuzz.amount % (T_NS - 1)
    if fuzz.stamp == 'negative':
        return -fuzz.amount
    if fuzz.topic == topics.REFERENCE:
        return c * T_NS + FAR + fuzz.amount * T_NS  # far_ahead
    return (c + AHEAD + fuzz.amount % 1700) * T_NS


# Ten valid states of x in the plant's name, 0.3 s to 1.2 s ahead of the newest tick (issue 25:
# the record took them as the first message of their samples).
SPOOFS = range(AHEAD, 4 * AHEAD + 1, AHEAD // 3)


def spoof(k: int) -> JointState:
    msg = JointState(name=['x'], position=[0.5])
    msg.header.stamp = stamp_msg(k * T_NS)
    msg.header.frame_id = OWNERS[topics.state('x')]
    return msg


def stamp_msg(ns: int) -> Time:
    sec, nanosec = divmod(ns, 1_000_000_000)
    return Time(sec=sec, nanosec=nanosec)


def message(fuzz: Fuzz, c: int) -> JointState | JointTrajectory:
    owner = OWNERS[fuzz.topic]
    sender = owner if fuzz.sender is None else fuzz.sender
    if fuzz.sender is not None and sender == owner:
        sender = 'intruder'  # another sender must not carry the owner's name
    if fuzz.topic == topics.REFERENCE:
        msg = JointTrajectory(joint_names=list(fuzz.names))
        for offset, pos, vel, acc in fuzz.points:
            sec, nanosec = divmod(offset, 1_000_000_000)
            msg.points.append(
                JointTrajectoryPoint(
                    positions=list(pos),
                    velocities=list(vel),
                    accelerations=list(acc),
                    time_from_start=Duration(sec=sec, nanosec=nanosec),
                )
            )
    else:
        position, velocity, effort = (list(a) for a in fuzz.arrays)
        msg = JointState(name=list(fuzz.names), position=position, velocity=velocity, effort=effort)
    msg.header.stamp = stamp_msg(stamp_of(fuzz, c))
    msg.header.frame_id = sender
    return msg


def test_generated_stream_is_malformed_where_it_impersonates() -> None:
    """The generator's own promise, checked on the stream the system test sends."""
    stream = generated_stream(MESSAGES)
    assert len(stream) == MESSAGES
    assert {f.topic for f in stream} == set(OWNERS)
    assert {f.stamp for f in stream} == set(STAMPS)
    impersonating = [f for f in stream if f.sender is None]
    assert 0.1 * MESSAGES < len(impersonating) < 0.4 * MESSAGES
    for f in impersonating:
        if f.stamp == 'next' and f.topic != topics.REFERENCE:
            _owner, needed = JOINT_STATE_TOPICS[f.topic]
            axis = f.topic.split('/')[2]
            values = dict(zip(FIELDS, f.arrays, strict=True))
            i = f.names.index(axis) if axis in f.names else None
            ok = i is not None and all(
                len(values[n]) > i and math.isfinite(values[n][i]) for n in needed
            )
            assert not ok, f
        if f.stamp == 'next' and f.topic == topics.REFERENCE:
            ok = (
                bool(f.points)
                and set(AXES) <= set(f.names)
                and all(o % T_NS == 0 for o, *_ in f.points)
                and all(len(p) >= 3 and all(map(math.isfinite, p)) for _, p, _, _ in f.points)
            )
            assert not ok, f


@pytest.mark.system
def test_every_node_survives_a_stream_of_bad_messages(ros_env, tmp_path) -> None:
    stream = generated_stream(MESSAGES)
    out = tmp_path / 'run'
    log = (tmp_path / 'runner.out').open('w')
    runner = subprocess.Popen(
        [
            *(sys.executable, '-m', 'mill_bringup.runner', 'slotting', '--duration', '2'),
            *('--compare-offline', '--quiet', '--output', str(out), '--record'),
        ],
        env=ros_env,
        stdout=log,
        stderr=subprocess.STDOUT,
        text=True,
    )
    ticks: list[int] = []
    inputs: dict[str, dict[str, int]] = {}  # status name -> the most drops per key seen
    sent: dict[str, int] = {}
    unrelated: list[int] = []  # stamps sent on UNRELATED once the recorder subscribed

    def on_diagnostics(msg: DiagnosticArray) -> None:
        for s in msg.status:
            if s.name.endswith(': inputs') and s.level != DiagnosticStatus.OK:
                seen = inputs.setdefault(s.name, {})
                for kv in s.values:  # the plant's: drops per topic; the others': TOPIC.dropped
                    if kv.key.endswith('.dropped') or s.name == 'plant: inputs':
                        seen[kv.key] = max(seen.get(kv.key, 0), int(kv.value))

    try:
        with ros_node('fuzzer') as (node, executor):
            node.create_subscription(
                Clock, topics.CLOCK, lambda m: ticks.append(from_stamp(m.clock) // T_NS), DATA_QOS
            )
            node.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, on_diagnostics, 100)
            # Publishers only once the job runs: before, they would count as the upstream
            # publishers the runner waits for before it starts the plant.
            while runner.poll() is None and (not ticks or ticks[-1] < 2 * TICK):
                executor.spin_once(timeout_sec=0.05)
            pubs = {
                t: node.create_publisher(
                    JointTrajectory if t == topics.REFERENCE else JointState, t, DATA_QOS
                )
                for t in OWNERS
            }
            other = node.create_publisher(JointState, UNRELATED, DATA_QOS)
            i, next_send = 0, time.monotonic()
            spoofed = False
            while runner.poll() is None:
                executor.spin_once(timeout_sec=0.001)
                if not spoofed and ticks:  # the attack of issue 25, once, with valid states
                    for ahead in SPOOFS:
                        pubs[topics.state('x')].publish(spoof(max(ticks) + ahead))
                    spoofed = True
                if time.monotonic() >= next_send and ticks:
                    fuzz = stream[i % len(stream)]
                    msg = message(fuzz, max(ticks))
                    pubs[fuzz.topic].publish(msg)
                    sent[fuzz.topic] = sent.get(fuzz.topic, 0) + 1
                    if fuzz.topic != topics.REFERENCE and other.get_subscription_count():
                        other.publish(msg)
                        unrelated.append(from_stamp(msg.header.stamp))
                    i, next_send = i + 1, next_send + PERIOD
            executor.spin_once(timeout_sec=0.1)
        code = runner.wait(timeout=600)
    finally:
        if runner.poll() is None:
            runner.kill()
            runner.wait()
        log.close()
    text = (tmp_path / 'runner.out').read_text()

    # The job ran to its end with every node alive: no node exited, and the summary exists.
    assert 'exited with code' not in text, text[-3000:]
    assert (out / 'summary.json').exists(), f'no summary (exit {code}):\n' + text[-3000:]
    summary = json.loads((out / 'summary.json').read_text())
    assert sum(sent.values()) >= MESSAGES, sent  # the stream went out at least once whole
    assert set(sent) == set(OWNERS), sent
    for path in (out / 'logs').glob('*.log'):
        assert 'Traceback' not in path.read_text(), path.name

    # Exit code 3 (a good job, its record not intact) only because foreign messages were seen.
    assert code == 3, text[-3000:]
    assert 'foreign messages were seen' in text, text[-3000:]
    assert summary['missing_samples'] == {}
    assert any(p.startswith('plant: ownership') for p in summary['problems'])
    assert set(summary['foreign']) == {
        *(f(a) for a in AXES for f in (topics.state, topics.estimate, topics.joint_command)),
        topics.REFERENCE,
    }, summary['foreign']
    # ... the spoofs with the owner's name among them: the runner left them out by their
    # publisher GID (the fuzzer's node), whatever their stamps, and names the fuzzer
    spoofed = {f.topic for f in stream if f.sender is None and f.stamp == 'far_ahead'}
    spoofed.add(topics.state('x'))
    assert spoofed <= set(summary['foreign']), summary['foreign']
    by_gid = [p for p in summary['problems'] if 'by its publisher GID' in p]
    assert all(any(f' on {t} from /fuzzer ' in p for p in by_gid) for t in spoofed), by_gid
    # ... and without them the record is the offline run's, sample for sample.
    assert summary['events'] == []
    assert summary['offline_max_difference'] == 0.0

    # The recorder kept running and closed a complete bag: every message of UNRELATED with a
    # sane stamp is in it up to the end of the recording (the stream went on until the runner
    # exited), those with a negative stamp were counted (with those of the other topics; the
    # bag's contract topics are checked by the record above).
    bag = open_bag(out / 'bag')
    recorded = [cdr_stamp_ns(d) for *_, d in bag.read(topics=[UNRELATED])]
    n = len(recorded)
    sane = [ns for ns in unrelated if ns >= 0]
    assert n > 50 and recorded == sane[:n], (n, len(sane))
    negative = sum(1 for ns in unrelated[: unrelated.index(sane[n - 1])] if ns < 0)
    assert negative > 5 and summary['bag']['dropped']['negative stamp'] >= negative
    assert set(summary['bag']['dropped']) <= {'negative stamp', 'stamp ahead'}
    assert bag.noted_counts(DROPPED) == summary['bag']['dropped']
    assert not (out / 'bag' / RESERVE_NAME).exists() and not bag.truncated
    assert sum(bag.counts.values()) == summary['bag']['messages']

    # Every node counted what it dropped, per input, on /diagnostics.
    for a in AXES:
        controller = inputs.get(f'{a}_controller: inputs', {})
        for t in (topics.state(a), topics.estimate(a), topics.REFERENCE):
            assert controller.get(f'{t}.dropped', 0) > 0, (a, t, controller)
        observer = inputs.get(f'{a}_observer: inputs', {})
        for t in (topics.state(a), topics.joint_command(a)):
            assert observer.get(f'{t}.dropped', 0) > 0, (a, t, observer)
        assert inputs.get('plant: inputs', {}).get(topics.joint_command(a), 0) > 0, inputs
