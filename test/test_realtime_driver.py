"""A hardware driver written from docs/hardware-driver.md alone drives the slotting job.

The driver below does not import mill_plant: it is what a user writes against the contract
("Write your own node"). Its machine is deliberately not the simulated plant: 30 % heavier
carriages, three times the Coulomb friction, a constant 20 N load on every axis (as if it
hung on a spring) and its own integrator; like every digital drive it applies the newest
command at its next tick (one sample of delay), holds it, and brakes an axis after 10 ticks
without a fresh one. It starts 0.5 mm away from the job's start point, so the job first
approaches it.

The graph runs with `run_scenario slotting --timing realtime --external plant --layout single`
(the driver in its own process, every other node in one container) at 100 Hz for 4 s of the
path after the approach move, told the driver's machine as docs/hardware-driver.md says a
different machine must be: the input gain b = 1 / (lead * mass) of its carriages (the
controllers' and observers' nominal model; with Table 1's gain the loop is unstable on this
machine, offline too), and observers tuned for the rate (omega_o = p_o = 30 rad/s; the
papers' 700 rad/s is a 1 kHz tuning). Every axis must track: no following-error trip (1 mm,
the scenario's limit: a trip brakes the axis and the summary reports it) and a maximum error
after the first second under 0.3 mm. The bound: offline, with this machine's mass,
friction and load and one sample of delay, the loop gives 0.053 / 0.001 / 0.058 mm on
x / y / z (the command is in docs/realtime.md, "A driver's machine"); on top come the
periods whose command arrives after the tick (about 0.2 % here); 0.3 mm is five times the
former and three times below the trip.

The job must also start only once the loop runs: no run of 10 job periods in a row (the
contract's brake limit) may go without a command (as the runner received them; this driver
does not report its own figures). Before the trajectory held the axes until every
controller had commanded (and until the runner heard the reference), 0 to 52 % of the
job's periods, from its start on, had no command the runner heard, while the container or
the runner were still being discovered (1 of 3 runs of this test with the old trajectory
gave 11 %: 44 periods from the start); with the hold, 0.00 % in three runs by hand. The share of
periods without a command is not bounded here: scattered ones come from the machine's load
(6.6 % on one axis in one CI run, 2.7 % on the others) and are a speed figure, measured by
`benchmark --realtime`.

Measured while writing this test (2-core machine), what does not hold: in the eight-process
layout the state -> command latency at 100 Hz is about 6 ms median and 16 ms p99, and the
loop trips; at 200 Hz with 100 rad/s observers it trips in the single layout too. Both are
open limits of real time here (docs/realtime.md, "Known limitations").
"""

from __future__ import annotations

import json
import math
import subprocess
import sys

import pytest

LAYOUT = 'single'
PERIOD = 0.01  # [s]
OMEGA_O = 30.0  # [rad/s]
# The driver's machine in the controllers' and observers' nominal model x'' = b tau + xi:
# b = 1 / (lead * mass), its lead and carriage masses (no screw inertia) as below.
LEAD = 0.003175 / (2 * math.pi)
MASS = {'x': 1.3 * 94.4, 'y': 1.3 * 70.39, 'z': 1.3 * 86.14}
INPUT_GAINS = [
    arg
    for a, m in MASS.items()
    for node in ('controller', 'observer')
    for arg in ('-p', f'{a}_{node}.input_gain={1.0 / (LEAD * m)!r}')
]

DRIVER = r"""
import math, sys, time
import rclpy
from rclpy.node import Node
from sensor_msgs.msg import JointState
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

T = float(sys.argv[1])                       # servo period [s]
AXES = ('x', 'y', 'z')
# Our own machine: Table 1 carriages, 30 % heavier, 3x friction, 20 N load, 3.175 mm pitch.
LEAD = 0.003175 / (2 * math.pi)
MASS = {'x': 1.3 * 94.4, 'y': 1.3 * 70.39, 'z': 1.3 * 86.14}
FRICTION, DAMPING, LOAD = 0.9, 5.0, 20.0
START = {'x': -0.075 + 0.0005, 'y': -0.105, 'z': -0.005}


class Driver(Node):
    def __init__(self):
        super().__init__('plant')
        self.x = dict(START)
        self.v = dict.fromkeys(AXES, 0.0)
        self.held = dict.fromkeys(AXES, math.nan)       # NaN: braked
        self.newest = {}
        self.late = dict.fromkeys(AXES, 0)
        self.published = []
        qos = 10
        self.pubs = {a: self.create_publisher(JointState, f'mill/{a}/state', qos) for a in AXES}
        self.diag = self.create_publisher(DiagnosticArray, '/diagnostics', 10)
        for a in AXES:
            self.create_subscription(JointState, f'mill/{a}/joint_command',
                                     lambda m, a=a: self.on_command(a, m), 1)
        self.create_timer(T, self.tick)

    def on_command(self, axis, msg):
        ns = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
        if msg.header.frame_id != f'{axis}_controller' or ns not in self.published:
            return                                      # not our controller, or no state of ours
        if list(msg.name) != [axis] or len(msg.effort) != 1:
            return
        self.newest[axis] = msg.effort[0]

    def tick(self):
        ns = time.time_ns()
        for a in AXES:
            if a in self.newest:                        # zero-order hold of the newest command
                self.held[a], self.late[a] = self.newest.pop(a), 0
            else:
                self.late[a] += 1
                if self.late[a] >= 10 and self.held[a] == self.held[a]:
                    self.held[a] = math.nan             # brake after 10 ticks without one
                    self.report(DiagnosticStatus.WARN, f'axis {a} braked: 10 late ticks')
        for a in AXES:
            msg = JointState(name=[a], position=[self.x[a]])
            msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(ns, 10**9)
            msg.header.frame_id = 'plant'
            self.pubs[a].publish(msg)
        self.published = (self.published + [ns])[-50:]
        for a in AXES:                                  # integrate one period, 10 substeps
            u = self.held[a]
            if u != u:
                self.v[a] = 0.0
                continue
            h = T / 10
            for _ in range(10):
                f = u / LEAD - DAMPING * self.v[a] - FRICTION * math.copysign(1, self.v[a]) - LOAD
                self.v[a] += h * f / MASS[a]
                self.x[a] += h * self.v[a]
        if int(ns / 1e9) != int((ns - T * 1e9) / 1e9):  # once a second
            self.report(DiagnosticStatus.OK, 'running')

    def report(self, level, message):
        late = [KeyValue(key=f'{a}.late', value=str(self.late[a])) for a in AXES]
        status = DiagnosticStatus(level=level, name='plant: driver', message=message, values=late)
        self.diag.publish(DiagnosticArray(status=[status]))


rclpy.init()
node = Driver()
try:
    rclpy.spin(node)
except KeyboardInterrupt:
    pass
"""


@pytest.mark.system
def test_a_driver_from_the_contract_alone_tracks_the_slotting_path(ros_env, tmp_path) -> None:
    script = tmp_path / 'rt_driver.py'
    script.write_text(DRIVER)
    assert 'mill_plant' not in DRIVER
    driver = subprocess.Popen(
        [sys.executable, str(script), repr(PERIOD)],
        env=ros_env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    out = tmp_path / 'run'
    try:
        proc = subprocess.run(
            [
                *(sys.executable, '-m', 'mill_bringup.runner', 'slotting'),
                *('--timing', 'realtime', '--external', 'plant', '--duration', '4'),
                *('--layout', LAYOUT),
                *('-p', f'*.sample_period={PERIOD!r}'),
                # The papers' observer poles (700 rad/s) are for 1 kHz; at 200 Hz, 100 rad/s.
                *(
                    '-p',
                    f'*_observer.gpi.omega_o={OMEGA_O!r}',
                    '-p',
                    f'*_observer.gpi.pole_o={OMEGA_O!r}',
                ),
                *('-p', 'trajectory.approach.max_distance=0.002'),
                *INPUT_GAINS,
                *('--output', str(out), '--quiet'),
            ],
            env=ros_env,
            capture_output=True,
            text=True,
            timeout=600,
        )
    finally:
        driver.terminate()
        driver_log = driver.communicate(timeout=30)[0]
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-3000:] + driver_log[-1000:]
    summary = json.loads((out / 'summary.json').read_text())
    assert summary['events'] == []
    assert not any('trip' in p for p in summary['problems']), summary['problems']
    metrics = {m['axis']: m for m in summary['metrics']}
    assert set(metrics) == {'x', 'y', 'z'}
    for axis, m in metrics.items():
        # A stall of the machine (>= 10 periods) brakes an axis by the contract and shows
        # here as a driver's WARN: the failure message says whether one came first.
        assert math.isfinite(m['max_error']) and m['max_error'] < 0.3e-3, (
            axis,
            m,
            summary['problems'],
            summary['drive'],
        )
        assert summary['drive'][axis]['longest_late_run'] < 10, (axis, summary['drive'])
