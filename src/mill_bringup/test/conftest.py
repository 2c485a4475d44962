"""Bags of a mill run as another writer (rosbags) writes them, for run_record and report tests."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pytest
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
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.registry import job_for
from mill_bringup.metrics import RunRecord
from mill_trajectory.config import build_job

from mill_bringup import scenario
from mill_common import topics

TS = typestore()
T = TS.types
WALL0 = 1_700_000_000_000_000_000

ForeignBag = Callable[..., tuple[Path, RunRecord]]


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
) -> tuple[Path, RunRecord]:
    """The offline simulation of 0.4 s of the job, written by rosbags' Writer as a recorder
    on wall time would (log time = receive time), with the contract's topics and types.

    With several namespaces each machine publishes the same run under its own; the job
    status carries the machine's namespace as hardware_id (the root's the old 'mill').
    foreign_status: first a job status of another machine ('/other') with a wrong end_time.
    """
    from rosbags.rosbag2 import StoragePlugin, Writer

    scen = scenario.load('slotting')
    scen.add_override('trajectory.duration=0.4')
    rec = simulate(job_for(scen))
    job = build_job(scen.parameters('trajectory'))
    n = rec.t.size
    dt_ns = 1_000_000
    s = rec.signals
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    path = directory / f'foreign_{storage}'
    with Writer(path, version=9, storage_plugin=plugin) as w:
        conns = {}

        def put(topic: str, msgtype: str, k: int, msg: Any) -> None:
            for space in namespaces:
                name = topics.qualify(topic, space)
                if name not in conns:
                    conns[name] = w.add_connection(name, msgtype, typestore=TS)
                w.write(conns[name], WALL0 + k * 3_100_000 + len(conns), ser(msg))
                if name == topics.DIAGNOSTICS:
                    break  # global: once

        def job_status(end_time: float, machine: str) -> Any:
            return status(
                level=0,
                name='trajectory: job',
                message='job running',
                hardware_id=machine,
                values=[kv(key='state', value='running'), kv(key='end_time', value=repr(end_time))],
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
                    header=header(ns), status=[job_status(job.end_time, m) for m in machines]
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
    """foreign_bag(storage, feed=False) -> (bag path, the offline RunRecord it holds)."""

    def make(storage: str, feed: bool = False, **kwargs: Any) -> tuple[Path, RunRecord]:
        return write_foreign_bag(tmp_path, storage, feed, **kwargs)

    return make
