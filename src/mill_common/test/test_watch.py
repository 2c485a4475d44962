"""InputWatch: silence levels, outages, and the start-up's silence that is no outage."""

from __future__ import annotations

from mill_common.watch import InputWatch, Level


def _watch() -> InputWatch:
    return InputWatch('mill/x/state', 'plant', warn_after=1.0, error_after=10.0)


def test_silence_levels_count_from_the_last_message() -> None:
    w = _watch()
    assert w.waiting and w.level(100.0) is Level.OK  # never heard: waiting, not silent
    w.heard(0.0)
    assert [w.level(t) for t in (0.5, 1.0, 9.9, 10.0)] == [
        Level.OK,
        Level.WARN,
        Level.WARN,
        Level.ERROR,
    ]


def test_an_ended_silence_is_an_outage_with_its_length() -> None:
    w = _watch()
    w.heard(0.0)
    assert w.heard(0.5) is None
    assert w.heard(2.0) == 1.5
    assert (w.outages, w.last_outage) == (1, 1.5)


def test_a_silence_of_the_start_up_is_no_outage() -> None:
    w = _watch()
    w.heard(0.0)
    assert w.heard(2.0, counts=False) is None  # step 0 held while discovery joins the graph
    assert w.outages == 0
    assert w.heard(4.0) == 2.0  # from then on silences count
