"""What every paper's report uses: the axis of the one-axis papers, one DFT bin, the
verdict word. ROS-free."""

from __future__ import annotations

import math

import numpy as np

X = 0  # the one-axis papers' experiments run on the x axis


def amplitude(t: np.ndarray, x: np.ndarray, f: float) -> float:
    """Single-sided amplitude of the f [Hz] component of x(t) (one DFT bin, no window)."""
    return float(2.0 * abs(np.mean(x * np.exp(-2j * math.pi * f * t))))


def verdict(holds: bool) -> str:
    return 'agrees' if holds else 'DISAGREES'
