"""The ROS-free rules of ros2_control's topic pair (mill_plant.topic_pair): which command
shape the drive takes, which stamps are recent, and the intake of commands that name no
sender in frame_id (topic_based_ros2_control leaves it empty)."""

from __future__ import annotations

import math

import pytest
from mill_common.checks import FOREIGN, OWNER, UNKNOWN, Sender
from mill_common.parameters import ParameterError
from mill_plant.command_intake import Accepted, CommandIntake, Dropped
from mill_plant.topic_pair import Ros2ControlParams, command_shape, sender_clock

AXES = ('x', 'y', 'z')
OWNER_NAME = 'topic_based_ros2_control_mill'


def test_efforts_for_the_drives_joints_have_the_shape_it_takes() -> None:
    assert command_shape(['x', 'y', 'z'], [], [], [0.1, -0.2, 0.0], AXES) is None
    assert command_shape(['z', 'x'], [], [], [0.1, math.nan], AXES) is None  # NaN: a brake


@pytest.mark.parametrize(
    ('names', 'position', 'velocity', 'effort', 'reason'),
    [
        (['x'], [0.1], [], [], 'position commands refused: the drive takes efforts only'),
        (['x'], [], [0.1], [], 'velocity commands refused: the drive takes efforts only'),
        (['x'], [0.1], [0.1], [0.2], 'position and velocity commands refused'),
        ([], [], [], [], 'names no joint'),
        (['x', 'spindle'], [], [], [1.0, 2.0], "joints ['spindle'] are not axes of this drive"),
        (['x', 'x'], [], [], [1.0, 2.0], "names a joint twice: ['x', 'x']"),
        (['x', 'y'], [], [], [1.0], "effort has 1 entries for the 2 joints ['x', 'y']"),
    ],
)
def test_any_other_shape_is_refused_with_its_reason(
    names: list[str], position: list[float], velocity: list[float], effort: list[float], reason: str
) -> None:
    got = command_shape(names, position, velocity, effort, AXES)
    assert got is not None and got.reason.startswith(reason) and '\n' not in got.reason


def test_a_stamp_on_the_senders_clock_must_be_recent() -> None:
    oldest, now, lead = 1_000_000_000, 1_200_000_000, 5_000_000
    assert sender_clock(oldest, oldest, now, lead) is None
    assert sender_clock(now + lead, oldest, now, lead) is None
    stale = sender_clock(oldest - 1, oldest, now, lead)
    assert stale is not None and 'older than every state this drive keeps' in stale.reason
    ahead = sender_clock(now + lead + 1_000_000, oldest, now, lead)
    assert ahead is not None and 'ahead of the drive' in ahead.reason
    none = sender_clock(now, None, now, lead)
    assert none is not None and none.reason == 'no state published yet'


def test_the_parameters_refuse_what_no_ros_name_can_be() -> None:
    assert Ros2ControlParams().commands_topic == ''  # off by default
    assert Ros2ControlParams(commands_topic='/robot_joint_commands').owner == OWNER_NAME
    with pytest.raises(ParameterError):
        Ros2ControlParams(commands_topic='robot joint commands')
    with pytest.raises(ParameterError):
        Ros2ControlParams(states_topic='')
    with pytest.raises(ParameterError):
        Ros2ControlParams(owner='')


def pair_intake() -> CommandIntake:
    return CommandIntake(dict.fromkeys(AXES, OWNER_NAME), None, lambda ns: None, False)


def test_without_frame_id_the_graphs_word_alone_decides() -> None:
    intake = pair_intake()
    owner = Sender(OWNER, f'/{OWNER_NAME}')
    assert intake.take('x', 10, '', AXES, [0.5, 0.0, 0.0], owner) == Accepted(0.5)
    rogue = intake.take('x', 20, '', AXES, [9.0, 0.0, 0.0], Sender(FOREIGN, '/rogue'))
    assert isinstance(rogue, Dropped) and rogue.foreign
    # Not yet in the graph, and nothing in frame_id to go by: refused until the graph says.
    unknown = intake.take('x', 30, '', AXES, [9.0, 0.0, 0.0], Sender(UNKNOWN, 'gid 01'))
    assert isinstance(unknown, Dropped) and unknown.foreign
    assert 'the graph does not show yet' in unknown.problem.reason
    # A frame_id that is given must agree.
    liar = intake.take('x', 40, 'x_controller', AXES, [9.0, 0.0, 0.0], owner)
    assert isinstance(liar, Dropped) and liar.foreign
    # Newest first, per axis; NaN from the owner is its brake request.
    old = intake.take('x', 5, '', AXES, [1.0, 0.0, 0.0], owner)
    assert isinstance(old, Dropped) and 'in the past' in old.problem.reason and not old.foreign
    braked = intake.take('y', 50, '', AXES, [0.0, math.nan, 0.0], owner)
    assert isinstance(braked, Accepted) and math.isnan(braked.effort) and braked.brake_request


def test_mills_own_commands_still_need_their_frame_id() -> None:
    intake = CommandIntake({'x': 'x_controller'}, None, lambda ns: None)
    got = intake.take('x', 10, '', ['x'], [0.5], Sender(OWNER, '/x_controller'))
    assert isinstance(got, Dropped) and got.foreign


def test_the_documented_ros2_control_block_agrees_with_the_drives_defaults() -> None:
    from pathlib import Path
    from xml.etree import ElementTree

    from mill_common.machine_urdf import joint_limits, machine_urdf

    doc = Path(__file__).resolve().parents[3] / 'docs' / 'hardware-driver.md'
    text = doc.read_text()
    section = text[text.index('### A `<ros2_control>` block') :]
    xml = section[section.index('```xml') + len('```xml') : section.index('```\n', 10)]
    block = ElementTree.fromstring(xml)
    hardware = block.find('hardware')
    assert hardware is not None
    assert hardware.findtext('plugin') == 'topic_based_ros2_control/TopicBasedSystem'
    params = {p.get('name'): p.text for p in hardware.findall('param')}
    defaults = Ros2ControlParams(commands_topic='robot_joint_commands')
    # The drive's relative names resolve so in the root namespace.
    assert params['joint_commands_topic'] == '/' + defaults.commands_topic
    assert params['joint_states_topic'] == '/' + defaults.states_topic
    assert params['trigger_joint_command_threshold'] == '-1'
    assert f'topic_based_ros2_control_{block.get("name")}' == defaults.owner
    # Its joints are the machine's, each commanded by effort alone.
    urdf = ElementTree.fromstring(machine_urdf(joint_limits([-1] * 3, [1] * 3, 0.5, [10] * 3)))
    machine = [j.get('name') for j in urdf.findall('joint')]
    joints = block.findall('joint')
    assert [j.get('name') for j in joints] == machine == list(AXES)
    for joint in joints:
        assert [c.get('name') for c in joint.findall('command_interface')] == ['effort']
        states = {s.get('name'): s for s in joint.findall('state_interface')}
        assert set(states) == {'position', 'velocity', 'effort'}
        assert states['effort'].find('param').text == 'nan'  # type: ignore[union-attr]
