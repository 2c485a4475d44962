"""Polynomial toolbox: the Sylvester matrix, the Diophantine equation, B = B⁺·B⁻."""

from __future__ import annotations

import numpy as np
import pytest
from mill_models.polynomials import (
    degree,
    pad,
    solve_diophantine,
    split_numerator,
    sylvester_matrix,
    trim,
)


def test_sylvester_solution_satisfies_the_equation() -> None:
    a = np.array([1.0, -1.2, 0.35, -0.02])
    b = np.array([0.4, 0.1, -0.05])
    c = np.poly([0.5, 0.4, -0.2, 0.1, 0.0, 0.3])
    x, y = solve_diophantine(a, b, c)
    assert len(x) == 4 and len(y) == 3  # deg x = deg c − deg a, deg y = deg a − 1
    np.testing.assert_allclose(np.polyadd(np.polymul(a, x), np.polymul(b, y)), c, atol=1e-13)
    m = sylvester_matrix(a, b, 3, 2)
    assert m.shape == (7, 7)
    # the columns are the shifted coefficient vectors of a and b
    np.testing.assert_array_equal(m[:4, 0], a)
    np.testing.assert_array_equal(m[-3:, -1], b)


def test_sylvester_system_is_singular_for_a_common_factor() -> None:
    a = np.poly([0.5, 0.2])
    b = np.poly([0.5])  # shares the root 0.5: no solution for a generic c
    assert np.linalg.cond(sylvester_matrix(a, b, 1, 1)) > 1e14
    assert np.linalg.cond(sylvester_matrix(a, np.poly([0.4]), 1, 1)) < 1e3


def test_trim_pad_and_degree_keep_the_polynomial() -> None:
    p = np.array([0.0, 0.0, 2.0, -1.0])
    np.testing.assert_array_equal(trim(p), [2.0, -1.0])
    assert degree(p) == 1
    np.testing.assert_array_equal(pad(p, 3), [0.0, 2.0, -1.0])
    np.testing.assert_array_equal(trim(np.zeros(3)), [0.0])
    with pytest.raises(ValueError, match='does not fit'):
        pad([1.0, 2.0, 3.0], 2)


def test_split_numerator_separates_the_zeros_by_radius() -> None:
    b = 3.0 * np.poly([0.4, -1.5])
    b_plus, b_minus = split_numerator(b, 1.0)
    np.testing.assert_allclose(b_plus, [1.0, -0.4])  # monic, the zero inside
    np.testing.assert_allclose(b_minus, [3.0, 4.5])  # the lead and the zero outside
    np.testing.assert_allclose(np.polymul(b_plus, b_minus), b)
