"""What a drive's configure decides before it makes anything (mill_plant.drive_setup):
which timing, backend and topic pair go together, and who commands each axis. ROS-free."""

from __future__ import annotations

from mill_plant.drive_setup import command_owners, configure_refusal
from mill_plant.topic_pair import Ros2ControlParams

OFF = Ros2ControlParams()
PAIR = Ros2ControlParams(commands_topic='robot_joint_commands', owner='topic_based_ros2_control_m')


def test_lockstep_needs_a_simulated_machine_and_no_topic_pair() -> None:
    assert configure_refusal(grid=True, simulated=True, pair=OFF) is None
    assert configure_refusal(grid=False, simulated=False, pair=PAIR) is None  # realtime
    real = configure_refusal(grid=True, simulated=False, pair=OFF)
    assert real == 'a real machine cannot run in lockstep: use timing realtime'
    paired = configure_refusal(grid=True, simulated=True, pair=PAIR)
    assert paired is not None and paired.startswith(
        'ros2_control.commands_topic needs timing realtime: '
    )
    assert '\n' not in paired


def test_each_axis_is_commanded_by_its_controller_or_by_the_pairs_owner() -> None:
    configured = ('x_controller', 'y_controller', '')  # z: anyone
    plain = command_owners(['x', 'z'], configured, OFF, 'plant')
    assert plain.axis_topics == {'x': 'x_controller', 'z': ''}  # the backend's axes only
    assert plain.axes == plain.axis_topics and plain.pair_topics is None
    paired = command_owners(['x', 'y', 'z'], configured, PAIR, 'plant')
    assert paired.axis_topics == {'x': 'x_controller', 'y': 'y_controller', 'z': ''}
    assert paired.axes == dict.fromkeys('xyz', 'topic_based_ros2_control_m')
    assert paired.pair_topics == {
        'robot_joint_commands': 'topic_based_ros2_control_m',
        'robot_joint_states': 'plant',  # the drive's own states
    }
