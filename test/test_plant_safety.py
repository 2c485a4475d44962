"""Plant safety: non-finite commands brake the axis, missing peers end the run with a name.

The test process plays the controller of x where a run needs one. Plant overrides use
`-p plant:NAME:=VALUE`: with the scenario file, a plain `-p NAME:=VALUE` loses to the
file's `plant:` entry (rcl stores plain `-p` under `/**`, and node-specific values win).
"""

from __future__ import annotations

import math
import time

import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from mill_common.ros import DATA_QOS, from_stamp, joint_state
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from sensor_msgs.msg import JointState

from mill_common import topics
from test.conftest import ros_node, wait_until

PLANT = 'mill_plant.plant_node'
CONTROLLER = 'mill_controllers.axis_controller_node'
T_NS = 1_000_000  # sample_period of the scenario file
STATE = topics.state('x')
COMMAND = topics.joint_command('x')


def plant_args(**values: str) -> list[str]:
    args = []
    for name, value in values.items():
        args += ['-p', f'plant:{name}:={value}']
    return args


class FakeController:
    """Answers /mill/x/state with torque(k) stamped like the state, for steps k < steps."""

    def __init__(self, node: Node, torque, steps: int) -> None:
        self.torque = torque
        self.steps = steps
        self.states: list[tuple[int, float]] = []  # (stamp ns, position) in arrival order
        self._pub = node.create_publisher(JointState, COMMAND, DATA_QOS)
        node.create_subscription(JointState, STATE, self._on_state, DATA_QOS)
        self._node = node

    def _on_state(self, msg: JointState) -> None:
        ns = from_stamp(msg.header.stamp)
        self.states.append((ns, msg.position[0]))
        k = ns // T_NS
        if k < self.steps:
            self._pub.publish(
                joint_state(ns, ('x',), effort=(self.torque(k),), sender='x_controller')
            )

    def matched(self) -> bool:
        node = self._node
        return node.count_publishers(STATE) >= 1 and node.count_subscribers(COMMAND) >= 1


def spin_until(executor: SingleThreadedExecutor, predicate, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        executor.spin_once(timeout_sec=0.1)
    return predicate()


def start_realtime_drive(start_node, sample_period: str):
    """A realtime drive of x alone, its states read by one subscriber."""
    return start_node(
        PLANT,
        'plant',
        *plant_args(
            axes='["x"]',
            min_subscribers='1',
            cutting_model='none',
            timing='realtime',
            sample_period=sample_period,
        ),
    )


# Command schedule of the braking test, by step k.
FINITE = 0.05  # N·m: ~99 N of drive force against 0.3 N of Coulomb friction
NAN_STEPS = range(50, 70)
INF_STEPS = range(70, 75)  # +inf, then -inf
STEPS = 100


def braking_torque(k: int) -> float:
    if k in NAN_STEPS:
        return math.nan
    if k in INF_STEPS:
        return math.inf if k < 73 else -math.inf
    return FINITE


@pytest.mark.system
def test_non_finite_command_brakes_the_axis(start_node) -> None:
    plant = start_node(
        PLANT,
        'plant',
        *plant_args(axes='["x"]', min_subscribers='1', cutting_model='none'),
    )
    truth: dict[int, JointState] = {}
    errors: list[DiagnosticStatus] = []

    def on_truth(msg: JointState) -> None:
        truth[from_stamp(msg.header.stamp) // T_NS] = msg

    def on_diagnostics(msg: DiagnosticArray) -> None:
        errors.extend(s for s in msg.status if s.level == DiagnosticStatus.ERROR)

    with ros_node('x_controller') as (node, executor):  # the owner the drive expects
        node.create_subscription(JointState, topics.GROUND_TRUTH, on_truth, DATA_QOS)
        node.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, on_diagnostics, 10)
        fake = FakeController(node, braking_torque, STEPS)

        def done() -> bool:
            last = fake.states[-1][0] // T_NS if fake.states else -1
            return last >= STEPS and STEPS - 1 in truth and bool(errors)

        assert wait_until(
            lambda: fake.matched() and node.count_publishers(topics.GROUND_TRUTH) >= 1, 60
        ), 'plant never matched'
        finished = spin_until(executor, done, 120)
        assert plant.alive(), plant.stop()[2]
        assert finished, (
            f'states up to {fake.states[-1] if fake.states else None}, '
            f'{len(truth)} truth samples, {len(errors)} errors'
        )

    # The plant kept stepping: stamps 0, T, 2T, ... without gaps (step 0 may be offered twice).
    stamps = [ns for ns, _ in fake.states]
    assert stamps == sorted(stamps)
    assert sorted(set(stamps)) == [k * T_NS for k in range(len(set(stamps)))]
    position = {ns // T_NS: y for ns, y in fake.states}
    assert all(math.isfinite(y) for y in position.values()), position

    # Braked: the position after a non-finite command is the position before it.
    non_finite = [k for k in range(STEPS) if not math.isfinite(braking_torque(k))]
    for k in non_finite:
        assert position[k + 1] == position[k], f'axis moved on step {k}'
    # ... and the finite commands did move it, before and after the braking.
    assert position[NAN_STEPS.start] > position[0]
    assert position[STEPS] > position[INF_STEPS.stop]

    # Ground truth (state of sample k): finite, x velocity 0 after every braked step.
    for k in range(STEPS):
        msg = truth[k]
        assert list(msg.name) == ['x', 'y', 'z']
        assert all(math.isfinite(v) for v in [*msg.position, *msg.velocity]), (k, msg)
        if math.isfinite(braking_torque(k)):
            assert math.isfinite(msg.effort[0]), (k, msg.effort)
        assert msg.position[0] == position[k]
    for k in non_finite:
        assert truth[k + 1].velocity[0] == 0.0, (k + 1, truth[k + 1].velocity)
    assert truth[NAN_STEPS.start].velocity[0] > 0.0

    # Reported on /diagnostics.
    assert any(s.name == 'plant: lockstep' and s.message == 'axis x braked' for s in errors), errors


@pytest.mark.system
def test_plant_ends_when_peers_never_appear(start_node) -> None:
    plant = start_node(PLANT, 'plant', *plant_args(startup_timeout='3.0'))
    code, _out, err = plant.wait(timeout=30)
    assert code == 3, err
    assert 'mill/x/joint_command' in err
    assert 'peers never appeared' in err


@pytest.mark.system
def test_plant_ends_when_a_command_stops_coming(start_node) -> None:
    plant = start_node(
        PLANT,
        'plant',
        *plant_args(
            axes='["x"]', min_subscribers='1', cutting_model='none', lockstep_timeout='2.0'
        ),
    )
    answered = 20
    with ros_node('x_controller') as (node, executor):  # the owner, then silent
        fake = FakeController(node, lambda k: FINITE, answered)
        assert wait_until(fake.matched, 60), 'plant never matched'
        assert spin_until(
            executor, lambda: any(ns >= answered * T_NS for ns, _ in fake.states), 60
        ), fake.states[-1:]
        # Stop answering, but keep the publisher (and so its node name) in the graph.
        code, _out, err = plant.wait(timeout=60)
    assert code == 3, err
    assert 'lockstep timeout' in err
    assert f'step {answered}' in err
    assert 'mill/x/joint_command' in err
    assert 'x_controller' in err


@pytest.mark.system
def test_controller_without_observer_is_named(start_node) -> None:
    controller = start_node(CONTROLLER, 'x_controller')
    plant = start_node(
        PLANT,
        'plant',
        *plant_args(
            axes='["x"]', min_subscribers='1', cutting_model='none', lockstep_timeout='3.0'
        ),
    )
    code, _out, err = plant.wait(timeout=90)
    assert code == 3, err
    assert 'lockstep timeout' in err
    assert 'mill/x/joint_command (from x_controller)' in err
    # The controller got the state of step 0 at least 3 s ago (the plant's timeout); it
    # warns every 2 s once it has waited 2 s. Give it two more periods, then read its log.
    time.sleep(4.5)
    assert controller.alive()
    _code, out, log = controller.stop()
    warnings = [
        line for line in (out + log).splitlines() if 'WARN' in line and 'waiting for' in line
    ]
    assert warnings, out + log
    assert any('mill/x/estimate' in line for line in warnings), warnings


@pytest.mark.system
def test_realtime_drive_holds_its_axes_before_the_first_command_without_a_fault(
    start_node,
) -> None:
    """Braked before the first command is where every realtime job starts: the drive says
    nothing about it. A brake asked for later (a non-finite command) is still an ERROR."""
    plant = start_realtime_drive(start_node, '0.01')
    statuses: list[DiagnosticStatus] = []
    answered: list[int] = []
    with ros_node('x_controller') as (node, executor):  # the owner the scenario names
        pub = node.create_publisher(JointState, COMMAND, DATA_QOS)

        def on_state(msg: JointState) -> None:
            # finite for 15 ticks (it reaches about 0.3 m/s, below the drive's speed
            # limit), then the brake request (NaN) of a tripped controller
            effort = FINITE if len(answered) < 15 else math.nan
            answered.append(from_stamp(msg.header.stamp))
            pub.publish(
                joint_state(
                    from_stamp(msg.header.stamp), ('x',), effort=(effort,), sender='x_controller'
                )
            )

        node.create_subscription(JointState, STATE, on_state, DATA_QOS)
        node.create_subscription(
            DiagnosticArray, topics.DIAGNOSTICS, lambda m: statuses.extend(m.status), 10
        )

        def braked_on_request() -> bool:
            return any('invalid command' in s.message for s in statuses)

        assert spin_until(executor, braked_on_request, 120), (
            f'{len(answered)} states answered; statuses: {[s.message for s in statuses]}'
        )
        spin_until(executor, lambda: False, 1.5)  # the running status after it, once a second
        assert plant.alive(), plant.stop()[2]
    errors = [s for s in statuses if s.level == DiagnosticStatus.ERROR]
    first_request = next(i for i, s in enumerate(errors) if 'invalid command' in s.message)
    assert errors[:first_request] == [], [s.message for s in errors]  # nothing before it
    assert any(s.message == 'axis x braked' for s in errors[first_request:]), [
        s.message for s in errors
    ]


@pytest.mark.system
def test_a_realtime_stop_holds_against_returning_commands_until_the_operator_releases(
    start_node,
) -> None:
    """The controller answers 30 states, falls silent for 30 (the drive stops the axis
    within 10: the held torque takes it off its course within a few), then answers again
    with the same torque: the axis stays where it stopped, and the drive says why.
    ~/release (std_srvs/Trigger) lets the next fresh command act: it moves."""
    from std_srvs.srv import Trigger

    plant = start_realtime_drive(start_node, '0.01')
    statuses: list[str] = []
    positions: list[tuple[int, float]] = []
    with ros_node('x_controller') as (node, executor):
        pub = node.create_publisher(JointState, COMMAND, DATA_QOS)

        def on_state(msg: JointState) -> None:
            ns = from_stamp(msg.header.stamp)
            positions.append((ns, msg.position[0]))
            if not 30 <= len(positions) < 60:  # silent for 30 ticks
                pub.publish(joint_state(ns, ('x',), effort=(FINITE,), sender='x_controller'))

        node.create_subscription(JointState, STATE, on_state, DATA_QOS)
        node.create_subscription(
            DiagnosticArray,
            topics.DIAGNOSTICS,
            lambda m: statuses.extend(s.message for s in m.status),
            10,
        )
        assert spin_until(executor, lambda: len(positions) > 100, 120), statuses
        stopped = [m for m in statuses if 'axis x: stopped: ' in m]
        assert len(stopped) == 1, statuses
        assert any('axis x: commands arriving, but stopped' in m for m in statuses), statuses
        held = [x for _, x in positions[62:]]  # from two ticks after the commands returned
        assert len(set(held)) == 1, held[:5]  # not moved by the returning commands
        client = node.create_client(Trigger, '/plant/release')
        assert client.wait_for_service(timeout_sec=60)
        future = client.call_async(Trigger.Request())
        executor.spin_until_future_complete(future, timeout_sec=60)
        assert future.result() is not None
        assert future.result().message == 'released x: braked until the next fresh command'
        count = len(positions)
        assert spin_until(executor, lambda: len(positions) > count + 20, 60)
        assert positions[-1][1] > held[-1]  # +0.05 N·m drives it towards +x again
        assert plant.alive(), plant.stop()[2]
    assert any('released by ~/release' in m for m in statuses), statuses


@pytest.mark.system
def test_a_sample_rate_the_machine_cannot_hold_is_said_and_the_drive_keeps_running(
    start_node,
) -> None:
    """10 kHz: a Python timer that publishes a state each tick cannot keep 0.1 ms periods
    (a tick costs about that much alone), so ticks come more than half a period late. The
    drive says so on /diagnostics within its first seconds, not only in the summary, and
    goes on ticking with its axis held."""
    plant = start_realtime_drive(start_node, '0.0001')
    statuses: list[DiagnosticStatus] = []
    states: list[int] = []
    with ros_node('watcher') as (node, executor):
        node.create_subscription(
            JointState, STATE, lambda m: states.append(from_stamp(m.header.stamp)), DATA_QOS
        )
        node.create_subscription(
            DiagnosticArray, topics.DIAGNOSTICS, lambda m: statuses.extend(m.status), 10
        )

        def said() -> list[DiagnosticStatus]:
            return [s for s in statuses if s.message.startswith('sample rate not held')]

        assert spin_until(executor, lambda: bool(said()), 120), [s.message for s in statuses]
        heard = len(states)
        spin_until(executor, lambda: len(states) > heard + 100, 30)
        assert len(states) > heard + 100  # still ticking
        assert plant.alive(), plant.stop()[2]
    status = said()[0]
    assert status.level == DiagnosticStatus.WARN
    assert '(0.05 ms) late in the last second' in status.message, status.message
    assert 'lower the rate or compose the nodes' in status.message


@pytest.mark.system
def test_a_foreign_publisher_on_a_command_topic_is_named_also_one_that_comes_later(
    start_node,
) -> None:
    """The drive looks at the publishers of its command and state topics once a second and
    names any but their owners, even ones that never send (it re-reads the names only when
    their number changes: the second intruder must still be found)."""
    plant = start_node(
        PLANT, 'plant', *plant_args(axes='["x"]', cutting_model='none', startup_timeout='120.0')
    )
    messages: list[str] = []
    with ros_node('first_intruder') as (node, executor):
        node.create_publisher(JointState, COMMAND, DATA_QOS)
        node.create_subscription(
            DiagnosticArray,
            topics.DIAGNOSTICS,
            lambda m: messages.extend(s.message for s in m.status if 'ownership' in s.name),
            10,
        )

        def named(who: str) -> bool:
            return any(who in m for m in messages)

        assert spin_until(executor, lambda: named('first_intruder'), 60), messages
        second = node.create_publisher(JointState, STATE, DATA_QOS)  # same node, other topic
        assert spin_until(executor, lambda: any(STATE in m for m in messages), 30), messages
        node.destroy_publisher(second)
        with ros_node('second_intruder') as (other, _):
            other.create_publisher(JointState, COMMAND, DATA_QOS)
            assert spin_until(executor, lambda: named('second_intruder'), 30), messages
    assert plant.alive(), plant.stop()[2]
