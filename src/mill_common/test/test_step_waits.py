"""A lockstep plant's step waits: counted over 10 ms, 100 ms and 1 s, read back from its status."""

from __future__ import annotations

from mill_common.step_waits import StepWaits, from_status


def test_waits_are_counted_over_each_threshold_and_read_back() -> None:
    waits = StepWaits()
    for w in (0.001, 0.0105, 0.05, 0.1, 0.1001, 2.8):
        waits.add(w)
    values = waits.status_values()
    assert values['waits_over_10ms'] == 5  # 10.5, 50, 100, 100.1 ms and 2.8 s
    assert values['waits_over_100ms'] == 2  # 100 ms itself is not over
    assert values['waits_over_1000ms'] == 1
    assert values['max_wait_ms'] == 2800.0
    assert abs(values['mean_wait_ms'] - 1e3 * 3.0616 / 6) < 1e-9
    assert from_status({k: str(v) for k, v in values.items()}) == {10: 5, 100: 2, 1000: 1}
    assert from_status({'mean_wait_ms': '1.0'}) is None  # a plant that does not count them
