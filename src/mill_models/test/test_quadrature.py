"""Simpson's rule."""

from __future__ import annotations

import numpy as np
import pytest
from mill_models.quadrature import simpson


def test_simpson_is_exact_for_cubics() -> None:
    t = np.linspace(0.0, 2.0, 5)
    assert simpson(t, t**3 - t) == pytest.approx(4.0 - 2.0)
    with pytest.raises(ValueError):
        simpson(t[:4], t[:4])
