"""The memory figures of a run: PSS read from /proc."""

from __future__ import annotations

import math
import resource

from mill_bringup.graph import pss_mb, vm_hwm_mb


def test_pss_of_this_process_is_at_most_its_peak_rss() -> None:
    pss = pss_mb()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    assert 1.0 < pss <= peak + 1.0


def test_a_process_that_is_gone_has_no_figure() -> None:
    assert math.isnan(pss_mb(2**22 + 12345))
    assert math.isnan(vm_hwm_mb(2**22 + 12345))
