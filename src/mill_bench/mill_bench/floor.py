"""The lockstep job's graph with empty callbacks: the floor that transport and executor set.

    python -m mill_bench.floor 3000          # start the eight processes, print JSON
    python -m mill_bench.floor 3000 listener # and a ninth that reads as the runner does
    python -m mill_bench.floor node x_observer 3000   # one process of it

The slotting job's topology in eight processes — a plant, a trajectory, three observers,
three controllers — with its hot-path messages at their sizes as CDR bytes (serialized
publish and take, as our nodes do), the same QoS and executor, and callbacks that only read
a stamp and answer: the plant sends the states of step k (and /clock every 10 steps), an
observer answers a state with an estimate, a controller answers state and estimate of k with
the command of k, the plant steps when it has the three commands. No runner listens. What
the real job runs slower than this is the cost of our own code per step.

With `listener`, a ninth process takes what the runner of a lockstep job takes (states,
estimates, reference and the plant's ground truth, which the plant then publishes) and does
nothing with it: the floor of a job that is watched, the cost of the runner's copies apart.

The JSON gives steps/s, the plant's CPU per step and the CPU per step of every process of
the graph (together: `cpu_ms_per_step`, as a job's summary counts it), from the first timed
step to the last. With MILL_FLOOR_TAKE=gid every reader but the clock's takes as the nodes
and the runner take an owned input (mill_common.graph_owner.GidSubscription: the bytes and
the publisher GID of each message, a Waitable of rclpy's executor): what the ownership
check by GID costs in transport alone.
"""

from __future__ import annotations

import json
import os
import signal
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from functools import partial
from typing import Any

from mill_common.codec import encode_clock, encode_joint_state, encode_joint_trajectory
from mill_common.env import apply_to_current_process
from mill_common.ros import DATA_QOS
from mill_common.timebase import stamp_ns

from mill_bench.pingpong import serve

AXES = ('x', 'y', 'z')
ROOT = '/mill_floor'
CLOCK = f'{ROOT}/clock'
REFERENCE = f'{ROOT}/reference'
T_NS = 1_000_000  # 1 kHz, as the job
CLOCK_EVERY = 10  # steps between /clock ticks (the plant's clock_period of 10 ms)
WARM_UP = 100  # steps before the timing starts (the processes settle)
ROLES = ('trajectory', *(f'{a}_{r}' for r in ('observer', 'controller') for a in AXES), 'plant')
LISTENER = 'listener'  # the ninth process, started last (the plant waits for it)
GROUND_TRUTH = f'{ROOT}/ground_truth'
_STAMP = struct.Struct('<iI')
STARTED = 'timing'  # the plant's line when the timed steps begin


def topic(axis: str, name: str) -> str:
    return f'{ROOT}/{axis}/{name}'


def stamp(data: bytes) -> int:
    return stamp_ns(*_STAMP.unpack_from(data, 4))


def _node(role: str, steps: int, listener: bool) -> int:
    """One process of the graph; the plant prints the result."""
    done = serve(f'floor_{role}', build(role, steps, listener), 600.0, like_nodes=True)
    if done and done[0] is not True:
        print(json.dumps(done[0]), flush=True)
    return 0


def _answer(node: Any, reads: list[str], write: str, frame: str, fields: int) -> None:
    """Publish `write` stamped k once every topic of `reads` has brought stamp k: a JointState
    of one joint with the last `fields` of position, velocity and effort (as the nodes do)."""
    from sensor_msgs.msg import JointState

    pub = node.create_publisher(JointState, write, DATA_QOS)
    newest = dict.fromkeys(reads, -1)
    arrays: list[tuple[float, ...]] = [(), (), ()]
    for i in range(3 - fields, 3):
        arrays[i] = (0.0,)
    axis = write.split('/')[2]

    def on(name: str, data: bytes) -> None:
        newest[name] = ns = stamp(data)
        if all(v == ns for v in newest.values()):
            pub.publish(encode_joint_state(ns, frame, (axis,), *arrays))

    for name in reads:
        _take(node, JointState, name, partial(on, name))


def _take(node: Any, msg_type: Any, name: str, callback: Callable[[bytes], None]) -> None:
    """A raw subscription as rclpy makes it; with MILL_FLOOR_TAKE=gid, as the nodes take an
    owned input (mill_common.graph_owner.GidSubscription: bytes and publisher GID)."""
    if os.environ.get('MILL_FLOOR_TAKE') == 'gid':
        from mill_common.graph_owner import GidSubscription

        GidSubscription(node, msg_type, name, lambda data, gid: callback(data), DATA_QOS)
    else:
        node.create_subscription(msg_type, name, callback, DATA_QOS, raw=True)


def _ignore(data: bytes) -> None:
    pass


def _clock_reader(node: Any, callback: Callable[[bytes], None] | None = None) -> None:
    from rosgraph_msgs.msg import Clock

    node.create_subscription(Clock, CLOCK, callback or (lambda data: None), DATA_QOS, raw=True)


def build(role: str, steps: int, listener: bool = False) -> Callable[[Any, list[Any]], None]:
    def watcher(node: Any, done: list[Any]) -> None:
        from sensor_msgs.msg import JointState
        from trajectory_msgs.msg import JointTrajectory

        reads = [topic(a, name) for a in AXES for name in ('state', 'estimate')]
        for name in (*reads, GROUND_TRUTH):
            _take(node, JointState, name, _ignore)
        _take(node, JointTrajectory, REFERENCE, _ignore)

    def observer(node: Any, done: list[Any]) -> None:
        from sensor_msgs.msg import JointState

        axis = role[0]
        _clock_reader(node)
        _take(node, JointState, topic(axis, 'joint_command'), _ignore)
        _answer(node, [topic(axis, 'state')], topic(axis, 'estimate'), role, 3)

    def controller(node: Any, done: list[Any]) -> None:
        from trajectory_msgs.msg import JointTrajectory

        axis = role[0]
        _clock_reader(node)
        _take(node, JointTrajectory, REFERENCE, _ignore)
        reads = [topic(axis, 'state'), topic(axis, 'estimate')]
        _answer(node, reads, topic(axis, 'joint_command'), role, 1)

    def trajectory(node: Any, done: list[Any]) -> None:
        from trajectory_msgs.msg import JointTrajectory

        pub = node.create_publisher(JointTrajectory, REFERENCE, DATA_QOS)
        point = ((0.0,) * 3, (0.0,) * 3, (0.0,) * 3, (), 0)
        points = [(*point[:4], i * T_NS) for i in range(CLOCK_EVERY)]
        _clock_reader(
            node, lambda data: pub.publish(encode_joint_trajectory(stamp(data), role, AXES, points))
        )

    def plant(node: Any, done: list[Any]) -> None:
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import JointState

        states = {a: node.create_publisher(JointState, topic(a, 'state'), DATA_QOS) for a in AXES}
        clock = node.create_publisher(Clock, CLOCK, DATA_QOS)
        truth = node.create_publisher(JointState, GROUND_TRUTH, DATA_QOS) if listener else None
        readers = 3 if listener else 2  # of each state: observer, controller (and listener)
        answered = dict.fromkeys(AXES, -1)
        k = [0]
        timing: list[float] = []

        def publish_step() -> None:
            ns = k[0] * T_NS
            if k[0] % CLOCK_EVERY == 0:
                clock.publish(encode_clock(ns))
            for a, pub in states.items():
                pub.publish(encode_joint_state(ns, role, (a,), position=(0.0,)))
            if truth is not None:  # as the plant's: velocity and disturbance of every axis
                zeros = (0.0,) * len(AXES)
                truth.publish(encode_joint_state(ns, role, AXES, (), zeros, zeros))

        def on_command(axis: str, data: bytes) -> None:
            answered[axis] = stamp(data)
            if any(v != k[0] * T_NS for v in answered.values()):
                return
            k[0] += 1
            if k[0] == WARM_UP:
                timing[:] = [time.perf_counter(), time.process_time()]
                print(STARTED, flush=True)  # the parent takes the CPU times of the graph
            if k[0] == WARM_UP + steps:
                wall = time.perf_counter() - timing[0]
                cpu = time.process_time() - timing[1]
                done.append({'steps_per_second': steps / wall, 'plant_cpu_ms': 1e3 * cpu / steps})
                return
            publish_step()

        for a in AXES:
            command = topic(a, 'joint_command')
            _take(node, JointState, command, partial(on_command, a))

        def ready() -> bool:
            return (
                clock.get_subscription_count() >= 7
                and all(p.get_subscription_count() >= readers for p in states.values())
                and (truth is None or truth.get_subscription_count() >= 1)
            )

        offered = [-1]

        def offer() -> None:  # the first step once all read; a lost step again (as the plant)
            if not done and offered[0] == k[0] and ready():
                publish_step()
            offered[0] = k[0]

        node.create_timer(0.5, offer)

    if role == LISTENER:
        return watcher
    if role == 'plant':
        return plant
    if role == 'trajectory':
        return trajectory
    return observer if role.endswith('observer') else controller


def measure(
    steps: int, env: dict[str, str], timeout: float = 600.0, listener: bool = False
) -> dict[str, float]:
    """Run the eight processes (nine with the listener) for `steps` steps (after a warm-up);
    steps/s, the plant's CPU per step and the CPU per step of every process of the graph
    together (`cpu_ms_per_step`, as a job's summary counts it). The other processes end
    with the plant."""
    from mill_bringup.graph import cpu_seconds

    procs = []
    roles = (*ROLES, LISTENER) if listener else ROLES
    extra = [LISTENER] if listener else []
    lines: list[str] = []
    by_process: list[list[float]] = []  # CPU times of each process at the start and end
    try:
        for role in roles:
            procs.append(
                subprocess.Popen(
                    [sys.executable, '-m', 'mill_bench.floor', 'node', role, str(steps), *extra],
                    env=env,
                    stdout=subprocess.PIPE,
                    text=True,
                )
            )
        plant = procs[ROLES.index('plant')]
        deadline = time.monotonic() + timeout
        timer = threading.Timer(timeout, plant.kill)  # a lost run ends the read below
        timer.start()
        try:
            assert plant.stdout is not None
            for line in plant.stdout:
                if line.strip() == STARTED or line.startswith('{'):
                    by_process.append([cpu_seconds(p.pid) for p in procs])
                lines.append(line)
                if line.startswith('{'):
                    break
            plant.wait(timeout=10)  # its result printed, it ends by itself
        finally:
            timer.cancel()
        if not any(line.startswith('{') for line in lines) and time.monotonic() >= deadline:
            raise RuntimeError(
                f'the empty-callback graph did not run {steps} steps within {timeout:g} s'
            )
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.send_signal(signal.SIGINT)
        for proc in procs:
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
    results = [line for line in lines if line.startswith('{')]
    if not results:
        raise RuntimeError(
            'the empty-callback plant printed no result '
            f'(exit {procs[ROLES.index("plant")].returncode})'
        )
    result = json.loads(results[-1])
    if len(by_process) == 2:
        used = [1e3 * (b - a) / steps for a, b in zip(*by_process, strict=True)]
        result['cpu_ms_per_step'] = sum(used)
        result['cpu_ms_per_step_by_process'] = dict(zip(roles, used, strict=True))
    return result


def main(argv: list[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    apply_to_current_process()
    listener = args[-1:] == [LISTENER] and len(args) > 1
    if listener:
        args = args[:-1]
    if args[:1] == ['node'] and len(args) == 3 and args[1] in (*ROLES, LISTENER):
        return _node(args[1], int(args[2]), listener)
    if len(args) == 1 and args[0].isdigit():
        print(json.dumps(measure(int(args[0]), dict(os.environ), listener=listener)))
        return 0
    print(__doc__)
    return 0 if args[:1] in (['-h'], ['--help']) else 2


if __name__ == '__main__':
    raise SystemExit(main())
