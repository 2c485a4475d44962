"""The feed drive's clamp in front of the force process (mill_plant.force_drive)."""

from __future__ import annotations

import numpy as np
import pytest
from mill_models.force_process import ForceProcessModel, ForceProcessParams, ForceProcessPlant
from mill_plant.force_drive import DrivenForceProcess

MODEL = ForceProcessModel(ForceProcessParams(depth_profile=[0.0, 2.0]))


def test_a_ramp_out_of_range_drives_the_process_like_the_clamped_ramp() -> None:
    lo, hi = 0.0, 6.0
    drive = DrivenForceProcess(ForceProcessPlant(MODEL), lo, hi, MODEL.sample_period / 8)
    pieces = drive.apply(4.0, 60.0, MODEL.sample_period)  # crosses hi within the sample
    assert len(pieces) == 2  # split at the clamp corner
    corner = (hi - 4.0) / 60.0
    reference = ForceProcessPlant(MODEL)
    reference.step(4.0, 60.0, corner)
    reference.step(hi, 0.0, MODEL.sample_period - corner)
    assert drive.plant.force == pytest.approx(reference.force, rel=1e-12)
    np.testing.assert_allclose(drive.plant.state, reference.state, rtol=1e-12)
    assert drive.clamp(-1.0) == lo and drive.clamp(9.0) == hi and drive.clamp(3.0) == 3.0


def test_an_empty_feed_range_is_refused() -> None:
    with pytest.raises(ValueError, match='empty'):
        DrivenForceProcess(ForceProcessPlant(MODEL), 2.0, 1.0)
