"""The timing strategies: how inputs are checked and which samples are stepped."""

from __future__ import annotations

import pytest
from mill_common.timing import Lockstep, Realtime, timing

DT = 1_000_000


def test_lockstep_keeps_every_sample_in_order_and_takes_repeats_as_offers() -> None:
    t = timing('lockstep', DT)
    pending = {3 * DT: 'c', DT: 'a', 2 * DT: 'b'}
    assert t.due(pending) == [DT, 2 * DT, 3 * DT] and len(pending) == 3
    stamps = t.stamps()
    stamps.accept(DT)
    assert t.is_offered_again(stamps, DT)
    assert t.problem(stamps, DT + 1, DT, DT) is not None  # off the grid
    assert t.problem(stamps, 3 * DT, DT, DT) is not None  # ahead of the plant
    assert t.problem(stamps, 2 * DT, DT, DT) is None
    assert t.off_grid([DT, 2 * DT + 5]) == 2 * DT + 5


def test_realtime_keeps_the_newest_refuses_repeats_and_takes_any_reference() -> None:
    t = Realtime(DT)
    pending = {1: 'a', 7: 'b', 3: 'c'}
    assert t.due(pending) == [7] and pending == {7: 'b'}
    stamps = t.stamps()
    stamps.accept(1234)
    assert t.problem(stamps, 1234, None, DT) is not None  # a repeat
    assert t.problem(stamps, 1000, None, DT) is not None  # the past
    assert t.problem(stamps, 1000, None, DT, history=True) is None
    assert t.depth() == 1 and t.depth(history=True) is None
    assert not t.is_offered_again(stamps, 1234)
    assert t.when(0).endswith('UTC') and Lockstep(DT).when(DT) == 'at t = 0.0010 s'


def test_an_unknown_timing_is_refused_in_one_line() -> None:
    with pytest.raises(ValueError, match="timing must be one of lockstep, realtime, got 'x'"):
        timing('x', DT)
