"""The transport delay the lockstep drive and the offline simulator share."""

from mill_plant.command_delay import CommandDelay


def test_commands_act_n_steps_late_with_zeros_before() -> None:
    d = CommandDelay(2, 2)
    assert [d([k, -k]) for k in (1.0, 2.0, 3.0)] == [[0.0, 0.0], [0.0, 0.0], [1.0, -1.0]]


def test_no_delay_passes_the_commands_on() -> None:
    assert CommandDelay(0, 1)([4.0]) == [4.0]
