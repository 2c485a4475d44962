"""A verdict under several readings: agrees / DISAGREES only when every reading says so."""

from __future__ import annotations

from mill_analysis.readings import flips, overall

AXES = ('the sample period', 'c_t')


def test_one_verdict_under_every_reading_is_that_verdict() -> None:
    assert overall({('0.1', 'a'): True, ('1', 'a'): True}, AXES) == 'agrees'
    assert overall({('0.1', 'a'): False, ('1', 'b'): False}, AXES) == 'DISAGREES'


def test_a_verdict_that_flips_names_the_readings_that_flip_it() -> None:
    verdicts = {
        ('0.1', 'a'): True,
        ('1', 'a'): False,
        ('0.1', 'b'): False,
        ('1', 'b'): False,
    }
    assert flips(verdicts, AXES) == list(AXES)
    assert overall(verdicts, AXES) == 'depends on the sample period, c_t'
    # c_t flips nothing where only the sample period was varied
    assert overall({('0.1', 'a'): True, ('1', 'a'): False}, AXES) == 'depends on the sample period'
