"""The drive's command intake: only the owner's answer to a state of the drive is taken; a
repeat of an answered step is ignored; a non-finite effort is the owner's brake request,
flagged once when it starts and once when valid commands return."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st
from mill_common.checks import Rejected
from mill_plant.command_intake import Accepted, CommandIntake, Dropped

T = 10_000_000  # [ns]


class Step:
    """A lockstep drive's `expected`: only the current step's stamp answers a state."""

    def __init__(self) -> None:
        self.k = 0

    def __call__(self, ns: int) -> Rejected | None:
        return None if ns == self.k * T else Rejected(f'stamp {ns} is not the current step')


def lockstep(owners: dict[str, str] | None = None) -> tuple[CommandIntake, Step]:
    step = Step()
    owners = owners if owners is not None else {'x': 'x_controller', 'y': 'y_controller'}
    return CommandIntake(owners, T, step), step


def x(intake: CommandIntake, ns: int, effort: float, sender: str = 'x_controller') -> object:
    return intake.take('x', ns, sender, ['x'], [effort])


def test_the_owners_command_for_the_current_step_is_accepted_once() -> None:
    intake, step = lockstep()
    assert x(intake, 0, 1.5) == Accepted(1.5)
    assert x(intake, 0, 2.5) is None  # the step answered again (re-offered): ignored
    step.k = 1
    assert x(intake, 0, 1.5) is None  # still the repeat of an answered step, not a drop
    assert x(intake, T, -0.5) == Accepted(-0.5)
    # An effort in a message naming several joints: the axis's own.
    step.k = 2
    got = intake.take('y', 2 * T, 'y_controller', ['x', 'y'], [9.0, 0.75])
    assert got == Accepted(0.75)


def test_another_sender_is_dropped_and_said_to_be_foreign() -> None:
    intake, _ = lockstep()
    got = x(intake, 0, 1.0, sender='intruder')
    assert isinstance(got, Dropped) and got.foreign
    assert got.problem.reason == "sent by 'intruder', not by its owner 'x_controller'"
    got = x(intake, 0, 1.0, sender='')
    assert isinstance(got, Dropped) and got.foreign and 'an unnamed publisher' in got.problem.reason
    assert x(intake, 0, 1.0) == Accepted(1.0)  # the owner's command for the step still counts
    # An answered step from a foreign sender is still dropped (and named), not ignored.
    got = x(intake, 0, 1.0, sender='intruder')
    assert isinstance(got, Dropped) and got.foreign
    # No owner configured: anyone may command the axis.
    anyone, _ = lockstep({'x': ''})
    assert x(anyone, 0, 3.0, sender='whoever') == Accepted(3.0)


def test_stamps_that_answer_no_state_are_dropped() -> None:
    intake, step = lockstep()
    step.k = 5
    for ns, reason in (
        (-T, 'negative stamp'),
        (5 * T + 1, 'off the sample grid'),
        (4 * T, 'is not the current step'),
        (6 * T, 'is not the current step'),
    ):
        got = x(intake, ns, 1.0)
        assert isinstance(got, Dropped) and not got.foreign and reason in got.problem.reason, ns
    assert x(intake, 5 * T, 1.0) == Accepted(1.0)
    # Older than the newest accepted one: in the past, dropped (not a harmless repeat).
    step.k = 4
    got = x(intake, 4 * T, 1.0)
    assert isinstance(got, Dropped) and 'in the past' in got.problem.reason


def test_a_malformed_command_is_dropped_and_the_step_stays_open() -> None:
    intake, _ = lockstep()
    for names, efforts, reason in (
        (['y'], [1.0], "no joint 'x'"),
        (['y', 'x'], [1.0], "effort has 1 entries, joint 'x' needs 2"),
        (['x'], [], "effort has 0 entries, joint 'x' needs 1"),
    ):
        got = intake.take('x', 0, 'x_controller', names, efforts)
        assert isinstance(got, Dropped) and not got.foreign and reason in got.problem.reason
    assert intake.invalid_commands == {'x': 0, 'y': 0}  # not brake requests
    assert x(intake, 0, 0.5) == Accepted(0.5)  # the step is still answerable


def test_a_brake_request_is_accepted_as_nan_and_flagged_when_it_starts_and_ends() -> None:
    intake, step = lockstep()
    flags = []
    for k, effort in enumerate([1.0, math.nan, math.inf, math.nan, 2.0, 3.0, -math.inf]):
        step.k = k
        got = x(intake, k * T, effort)
        assert isinstance(got, Accepted), (k, got)
        assert math.isfinite(got.effort) == math.isfinite(effort), k
        flags.append((got.brake_request, got.released))
    assert flags == [
        ('', False),
        ("effort of joint 'x' is nan", False),  # starts: said once
        ('', False),  # a tripped controller asks again every sample
        ('', False),
        ('', True),  # valid again: said once
        ('', False),
        ("effort of joint 'x' is -inf", False),  # a new brake request
    ]
    assert intake.invalid_commands == {'x': 4, 'y': 0}
    # Each axis has its own state: y's valid command releases nothing.
    got = intake.take('y', 6 * T, 'y_controller', ['y'], [1.0])
    assert got == Accepted(1.0)


def test_realtime_takes_any_newer_stamp_the_drive_published() -> None:
    published = {3, 1_000_007, 2_500_000}  # off any grid: the acquisition times
    intake = CommandIntake(
        {'x': 'x_controller'},
        None,
        lambda ns: None if ns in published else Rejected(f'stamp {ns} answers no state'),
    )
    assert x(intake, 1_000_007, 1.0) == Accepted(1.0)
    got = x(intake, 2_000_000, 1.0)
    assert isinstance(got, Dropped) and 'answers no state' in got.problem.reason
    got = x(intake, 3, 1.0)
    assert isinstance(got, Dropped) and 'in the past' in got.problem.reason
    assert x(intake, 2_500_000, 1.0) == Accepted(1.0)


messages = st.lists(
    st.tuples(
        st.integers(min_value=-2, max_value=12),  # the stamp, in periods
        st.sampled_from(['x_controller', 'other', '']),
        st.sampled_from([0.5, -1.0, math.nan, math.inf]),
        st.booleans(),  # the step moves on before this message
    ),
    max_size=60,
)


@settings(max_examples=300, deadline=None, derandomize=True)
@given(messages)
def test_accepted_stamps_increase_and_every_brake_request_is_counted(stream: list) -> None:
    intake, step = lockstep({'x': 'x_controller'})
    accepted: list[int] = []
    requests = 0
    requesting = False
    for periods, sender, effort, moves_on in stream:
        step.k += moves_on
        ns = periods * T
        got = x(intake, ns, effort, sender)
        if isinstance(got, Dropped):
            assert got.foreign == (sender != 'x_controller')
            continue
        if got is None:  # ignored: only ever the repeat of the last answered step
            assert accepted and ns == accepted[-1]
            continue
        assert sender == 'x_controller' and ns == step.k * T
        assert not accepted or ns > accepted[-1]
        accepted.append(ns)
        nan = math.isnan(got.effort)
        assert nan == (not math.isfinite(effort))
        requests += nan
        assert bool(got.brake_request) == (nan and not requesting)
        assert got.released == (not nan and requesting)
        requesting = nan
    assert intake.invalid_commands['x'] == requests


def test_the_owners_brake_request_wins_over_its_valid_command_of_the_same_step() -> None:
    from mill_common.checks import OWNER, Sender

    owner = Sender(OWNER, '/x_controller')
    intake, step = lockstep()
    assert intake.take('x', 0, 'x_controller', ['x'], [1.5], owner) == Accepted(1.5)
    got = intake.take('x', 0, 'x_controller', ['x'], [math.nan], owner)
    assert isinstance(got, Accepted) and math.isnan(got.effort) and got.brake_request
    # ... and a valid command after it does not take the step back
    assert intake.take('x', 0, 'x_controller', ['x'], [1.5], owner) is None
    step.k = 1
    assert intake.take('x', T, 'x_controller', ['x'], [0.5], owner) == Accepted(0.5, released=True)


def test_a_rogue_with_the_owners_frame_id_is_foreign_by_the_graphs_word() -> None:
    from mill_common.checks import FOREIGN, Sender

    intake, _ = lockstep()
    got = intake.take('x', 0, 'x_controller', ['x'], [10.0], Sender(FOREIGN, '/rogue'))
    assert isinstance(got, Dropped) and got.foreign
    assert got.problem.reason == "sent by /rogue, not by its owner 'x_controller'"
    # it moved no stamp: the owner's command for the step still counts
    assert x(intake, 0, 1.0) == Accepted(1.0)


def test_commands_of_two_publishers_claiming_the_owners_name_brake_the_axis() -> None:
    from mill_common.checks import CONTESTED, Sender

    claim = Sender(CONTESTED, '/x_controller', ('/x_controller (gid a)', '/x_controller (gid b)'))
    intake, step = lockstep()
    got = intake.take('x', 0, 'x_controller', ['x'], [3.0], claim)
    assert isinstance(got, Accepted) and math.isnan(got.effort) and got.contested
    assert "2 publishers claim to be 'x_controller'" in got.brake_request
    assert 'gid a' in got.brake_request and 'gid b' in got.brake_request
    assert intake.take('x', 0, 'x_controller', ['x'], [3.0], claim) is None  # the other's
    step.k = 5
    got = intake.take('x', T, 'x_controller', ['x'], [3.0], claim)
    assert isinstance(got, Dropped)  # not the step the drive expects: dropped


def test_a_publisher_the_graph_has_not_named_is_refused_while_it_shows_the_owner() -> None:
    # Issue 37 item 2: a second x_controller started mid-job; until discovery named it,
    # its frame_id decided, and its 10 N·m commands, first for the step, drove x 1 mm.
    from mill_common.checks import UNKNOWN, Sender

    unnamed = 'an unknown publisher (gid 01.02)'
    intake, _ = lockstep()
    copy = Sender(UNKNOWN, unnamed, ('/x_controller (gid 0a.0b)',))
    got = intake.take('x', 0, 'x_controller', ['x'], [10.0], copy)
    assert isinstance(got, Dropped) and not got.foreign  # not known to be foreign either
    assert got.problem.reason == (
        f'{unnamed}, not named by the graph yet, while it shows /x_controller (gid 0a.0b): '
        'refused until named'
    )
    assert x(intake, 0, 1.0) == Accepted(1.0)  # the owner's command for the step counts
    # Before the graph shows the owner at all (a drive's start), its frame_id decides.
    intake, _ = lockstep()
    assert intake.take('x', 0, 'x_controller', ['x'], [1.0], Sender(UNKNOWN, unnamed)) == (
        Accepted(1.0)
    )
