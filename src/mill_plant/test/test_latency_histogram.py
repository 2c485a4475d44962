"""The drive's latency histogram reports what numpy.percentile reports, to its 1 µs bins."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st
from mill_plant.latency_histogram import BIN_NS, BINS, LatencyHistogram


def binned(ns: int) -> int:
    """What the histogram keeps of a latency: its 1 µs bin, or the value outside the bins."""
    i = (ns + BIN_NS // 2) // BIN_NS
    return i * BIN_NS if 0 <= i < BINS else ns


@given(st.lists(st.integers(-5_000_000, 300_000_000), min_size=1, max_size=300))
def test_quantiles_equal_numpys_of_the_binned_values(latencies: list[int]) -> None:
    h = LatencyHistogram()
    for ns in latencies:
        h.add(ns)
    kept = np.array([binned(ns) for ns in latencies], dtype=float)
    got = h.stats()
    assert math.isclose(got['median'], np.percentile(kept, 50) * 1e-9, abs_tol=1e-15)
    assert math.isclose(got['p99'], np.percentile(kept, 99) * 1e-9, abs_tol=1e-15)
    assert got['max'] == max(latencies) * 1e-9  # the max is exact


def test_every_quantile_is_within_half_a_microsecond_of_the_exact_one() -> None:
    rng = np.random.default_rng(3)
    latencies = rng.integers(100_000, 20_000_000, size=5000)
    h = LatencyHistogram()
    for ns in latencies.tolist():
        h.add(ns)
    got = h.stats()
    assert abs(got['median'] - np.median(latencies) * 1e-9) <= 0.5e-6
    assert abs(got['p99'] - np.percentile(latencies, 99) * 1e-9) <= 0.5e-6


def test_no_latency_yet_is_nan() -> None:
    assert all(math.isnan(v) for v in LatencyHistogram().stats().values())
