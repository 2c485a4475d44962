"""Bags of a mill run as another writer (rosbags) writes them, for bag_run and report tests.

The run is made up (`a_run`): every signal known at every sample, no simulation needed."""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mill_analysis.record import RunRecord
from mill_bag.types import (
    DIAGNOSTIC_ARRAY,
    FLOAT64,
    HEADER,
    JOINT_STATE,
    JOINT_TRAJECTORY,
    TIME,
    WRENCH_STAMPED,
    typestore,
)

from mill_common import topics

TS = typestore()
T = TS.types
WALL0 = 1_700_000_000_000_000_000

ForeignBag = Callable[..., tuple[Path, RunRecord]]
END_TIME = 0.4  # [s]: samples 0 .. 400 at 1 kHz
DT_NS = 1_000_000


def a_run(n: int = 401, dt_ns: int = DT_NS) -> RunRecord:
    """n samples of a three-axis run, every signal finite: each axis follows a ramp with a
    60 Hz error of a few µm under a 60 Hz cutting disturbance, as a slotting cut does."""
    rec = RunRecord.empty(n, dt_ns / 1e9)
    t = rec.t[:, None]
    i = np.arange(3)[None, :]
    tone = np.sin(2 * np.pi * 60.0 * t + i)
    speed = np.array([[0.0, 3e-3, -1e-3]])  # [m/s]
    s = rec.signals
    s['reference'][:] = 0.01 * i + speed * t
    s['reference_velocity'][:] = speed + 0.0 * t
    s['position'][:] = s['reference'] + 5e-6 * tone
    s['true_velocity'][:] = speed + 2e-3 * np.cos(2 * np.pi * 60.0 * t + i)
    s['estimate_velocity'][:] = s['true_velocity'] + 1e-5 * tone
    s['true_disturbance'][:] = 1.0 + i + 2.0 * tone
    s['estimate_disturbance'][:] = s['true_disturbance'] + 0.2 * np.cos(2 * np.pi * 60.0 * t)
    s['torque'][:] = 0.05 * (i + 1) + 0.1 * tone
    s['force'][:] = 50.0 * (i + 1) + 100.0 * tone
    return rec


def stamp(ns: int) -> Any:
    return T[TIME](sec=ns // 10**9, nanosec=ns % 10**9)


def header(ns: int) -> Any:
    return T[HEADER](stamp=stamp(ns), frame_id='')


def arr(values: Sequence[float]) -> np.ndarray:
    return np.array(values, dtype=np.float64)


def joint_state(
    ns: int,
    names: Sequence[str],
    position: Sequence[float] = (),
    velocity: Sequence[float] = (),
    effort: Sequence[float] = (),
) -> Any:
    return T[JOINT_STATE](
        header=header(ns),
        name=list(names),
        position=arr(position),
        velocity=arr(velocity),
        effort=arr(effort),
    )


def wrench(ns: int, f: Sequence[float]) -> Any:
    v3 = T['geometry_msgs/msg/Vector3']
    w = T['geometry_msgs/msg/Wrench'](force=v3(x=f[0], y=f[1], z=f[2]), torque=v3(x=0, y=0, z=0))
    return T[WRENCH_STAMPED](header=header(ns), wrench=w)


def ser(msg: Any) -> bytes:
    return bytes(TS.serialize_cdr(msg, msg.__msgtype__))


def write_foreign_bag(
    directory: Path,
    storage: str,
    feed: bool = False,
    namespaces: Sequence[str] = ('/',),
    foreign_status: bool = False,
    start_ns: int | None = None,
    notes: Mapping[str, str] | None = None,
    drop: Mapping[str, Collection[int]] | None = None,
) -> tuple[Path, RunRecord]:
    """`a_run()`, written by rosbags' Writer as a recorder on wall time would (log time =
    receive time), with the contract's topics and types.

    With several namespaces each machine publishes the same run under its own; the job
    status carries the machine's namespace as hardware_id (the root's the old 'mill').
    foreign_status: first a job status of another machine ('/other') with a wrong end_time.
    start_ns: the job status says the job started then (as a realtime job's does).
    notes: the bag's custom_data (what run_scenario --record says of its bag).
    drop: per contract topic, the samples k the recorder lost (not written).
    """
    from rosbags.rosbag2 import StoragePlugin, Writer

    rec = a_run()
    n = rec.t.size
    dt_ns = DT_NS
    s = rec.signals
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    path = directory / f'foreign_{storage}'
    with Writer(path, version=9, storage_plugin=plugin) as w:
        for key, value in (notes or {}).items():
            w.set_custom_data(key, value)
        conns = {}

        def put(topic: str, msgtype: str, k: int, msg: Any) -> None:
            if k in (drop or {}).get(topic, ()):
                return
            for space in namespaces:
                name = topics.qualify(topic, space)
                if name not in conns:
                    conns[name] = w.add_connection(name, msgtype, typestore=TS)
                w.write(conns[name], WALL0 + k * 3_100_000 + len(conns), ser(msg))
                if name == topics.DIAGNOSTICS:
                    break  # global: once

        def job_status(end_time: float, machine: str) -> Any:
            values = [kv(key='state', value='running'), kv(key='end_time', value=repr(end_time))]
            if start_ns is not None:
                values.append(kv(key='start_stamp_ns', value=str(start_ns)))
            return status(
                level=0,
                name='trajectory: job',
                message='job running',
                hardware_id=machine,
                values=values,
            )

        status = T['diagnostic_msgs/msg/DiagnosticStatus']
        kv = T['diagnostic_msgs/msg/KeyValue']
        if foreign_status:
            other = [job_status(0.1, '/other')]
            put(
                topics.DIAGNOSTICS,
                DIAGNOSTIC_ARRAY,
                0,
                T[DIAGNOSTIC_ARRAY](header=header(0), status=other),
            )
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
                machines = [s if s != '/' else 'mill' for s in namespaces]
                diag = T[DIAGNOSTIC_ARRAY](
                    header=header(ns), status=[job_status(END_TIME, m) for m in machines]
                )
                put(topics.DIAGNOSTICS, DIAGNOSTIC_ARRAY, k, diag)
                if feed:  # a feed override (issue 4) as std_msgs/Float64, 1.0 -> 0.8
                    value = 1.0 - 0.2 * k / n
                    put(
                        topics.FEED_OVERRIDE,
                        FLOAT64,
                        k,
                        T[FLOAT64](data=value),
                    )
    return path, rec


@pytest.fixture
def foreign_bag(tmp_path: Path) -> ForeignBag:
    """foreign_bag(storage, feed=False) -> (bag path, the RunRecord it holds)."""

    def make(storage: str, feed: bool = False, **kwargs: Any) -> tuple[Path, RunRecord]:
        return write_foreign_bag(tmp_path, storage, feed, **kwargs)

    return make
