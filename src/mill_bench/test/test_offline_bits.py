"""The offline records' fingerprint sees every bit and nothing else."""

from __future__ import annotations

import numpy as np
from mill_analysis.record import RunRecord
from mill_bench.offline_bits import fingerprint


def test_a_fingerprint_sees_one_bit_and_a_nan_payload() -> None:
    a = RunRecord.empty(5, 0.001)
    a.signals['position'][:] = np.linspace(0.0, 1.0, 15).reshape(5, 3)
    b = RunRecord.empty(5, 0.001)
    b.signals['position'][:] = a.signals['position']
    assert fingerprint(a) == fingerprint(b)  # equal values, separate arrays
    bits = b.signals['position'].view(np.int64)
    bits[2, 1] ^= 1  # one ulp
    assert fingerprint(a) != fingerprint(b)
    bits[2, 1] ^= 1
    assert fingerprint(a) == fingerprint(b)
    nan = b.signals['torque'].view(np.int64)
    nan[0, 0] ^= (
        1  # another NaN: the same value to np.array_equal(equal_nan=True), not the same bits
    )
    assert np.isnan(b.signals['torque'][0, 0])
    assert fingerprint(a) != fingerprint(b)
