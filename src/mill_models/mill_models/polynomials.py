"""Polynomials in z as numpy arrays (highest power first), and the Diophantine equation.

The pole-placement design of Rubio 2013 eq. (10) (mill_controllers.model_reference) needs
four things done with polynomials:

- trim, degree, pad: the same polynomial with or without leading zeros;
- split_numerator: B = B⁺·B⁻, the zeros to cancel (inside a radius) and the rest;
- sylvester_matrix: the linear map (x, y) ↦ a·x + b·y on the coefficients;
- solve_diophantine: x, y with a·x + b·y = c, solved on the Sylvester matrix (a unique
  solution when a and b are coprime and the system is square).

Nothing here knows about a plant or a controller.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

# A polynomial's coefficients, highest power first: a list or an array.
Poly = Sequence[float] | np.ndarray


def trim(p: Poly, tol: float = 0.0) -> np.ndarray:
    """Drop leading coefficients with |c| <= tol (keeps at least one coefficient)."""
    c = np.atleast_1d(np.asarray(p, dtype=float))
    nz = np.nonzero(np.abs(c) > tol)[0]
    return c[nz[0] :].copy() if nz.size else np.zeros(1)


def degree(p: Poly) -> int:
    return len(trim(p)) - 1


def pad(p: Poly, length: int) -> np.ndarray:
    """Left-pad with zeros to `length` coefficients (same polynomial)."""
    c = trim(p)
    if len(c) > length:
        raise ValueError(f'polynomial of degree {len(c) - 1} does not fit {length} coefficients')
    return np.concatenate([np.zeros(length - len(c)), c])


def sylvester_matrix(a: Poly, b: Poly, deg_x: int, deg_y: int) -> np.ndarray:
    """M with M·[x; y] = coefficients of a·x + b·y (deg x = deg_x, deg y = deg_y).

    Columns are the shifted coefficient vectors z^{deg_x−i}·a and z^{deg_y−j}·b, rows the
    powers of z from deg_x + deg a down to 0; square when deg b <= deg a and
    deg_y = deg a − 1 (the Sylvester resultant matrix when also deg_x = deg b − 1).
    """
    ca = trim(a)
    cb = trim(b)
    rows = max(len(ca) + deg_x, len(cb) + deg_y)
    m = np.zeros((rows, deg_x + 1 + deg_y + 1))
    for i in range(deg_x + 1):
        shift = deg_x - i  # column i multiplies z^{shift}
        end = rows - shift
        m[end - len(ca) : end, i] = ca
    for j in range(deg_y + 1):
        shift = deg_y - j
        end = rows - shift
        m[end - len(cb) : end, deg_x + 1 + j] = cb
    return m


def solve_diophantine(a: Poly, b: Poly, c: Poly) -> tuple[np.ndarray, np.ndarray]:
    """(x, y) with a·x + b·y = c, deg y = deg a − 1, deg x = deg c − deg a.

    Needs a and b coprime and deg b <= deg x + 1 (else the system is not square);
    solved with numpy.linalg.solve on the Sylvester matrix.
    """
    ca = trim(a)
    cb = trim(b)
    cc = trim(c)
    na = len(ca) - 1
    deg_x = len(cc) - 1 - na
    deg_y = na - 1
    if deg_x < 0 or deg_y < 0:
        raise ValueError('deg c must be >= deg a >= 1')
    m = sylvester_matrix(ca, cb, deg_x, deg_y)
    if m.shape[0] != m.shape[1]:
        raise ValueError(f'Diophantine system is not square: {m.shape} (deg b too high)')
    sol = np.linalg.solve(m, pad(cc, m.shape[0]))
    return sol[: deg_x + 1], sol[deg_x + 1 :]


def split_numerator(b: Poly, radius: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """B = B⁺·B⁻: B⁺ monic with the zeros |z| < radius, B⁻ the rest times the lead."""
    cb = trim(b)
    zeros = np.roots(cb)
    inside = zeros[np.abs(zeros) < radius]
    outside = zeros[np.abs(zeros) >= radius]
    b_plus = np.real(np.poly(inside)) if inside.size else np.ones(1)
    b_minus = cb[0] * (np.real(np.poly(outside)) if outside.size else np.ones(1))
    return np.atleast_1d(b_plus), np.atleast_1d(b_minus)
