"""The AIC's dense solve (formation_env.wake.aic.lu_solve_inplace; issue 26: the pivot row copied to scratch so that
the row updates vectorise): Gaussian elimination with partial pivoting, bit for bit the textbook loop (numpy twin
below, each element updated by the same operations in the same order), and the solution of a x = b to round-off."""

import numpy as np
import pytest

from formation_env.wake.aic import lu_solve_inplace


def _textbook(a, rhs):
    """Right-looking elimination with partial pivoting, row by row in numpy (the loop lu_solve_inplace ran before)."""
    a, rhs = a.copy(), rhs.copy()
    n = a.shape[0]
    for k in range(n):
        p = k + int(np.argmax(np.abs(a[k:, k])))
        if abs(a[p, k]) <= abs(a[k, k]):  # the kernel swaps only on a strictly larger pivot
            p = k
        if p != k:
            a[[k, p]] = a[[p, k]]
            rhs[[k, p]] = rhs[[p, k]]
        piv = a[k, k]
        if piv == 0.0:
            piv = 1e-300
            a[k, k] = piv
        for i in range(k + 1, n):
            m = a[i, k] / piv
            if m != 0.0:
                a[i, k + 1:] -= m * a[k, k + 1:]
                rhs[i] -= m * rhs[k]
    for k in range(n - 1, -1, -1):
        s = rhs[k]
        for j in range(k + 1, n):
            s -= a[k, j] * rhs[j]
        rhs[k] = s / a[k, k]
    return rhs


@pytest.mark.parametrize("n", [1, 3, 20, 50, 90])
def test_bit_for_bit_the_textbook_loop_and_solves(n):
    rng = np.random.default_rng(n)
    for trial in range(4):
        a = rng.standard_normal((n, n)) + (0.3 * n * np.eye(n) if trial % 2 else 0.0)  # odd: diagonally dominant
        if n > 3 and trial == 2:
            a[2, 2] = 0.0  # a zero on the diagonal: a row swap
        b = rng.standard_normal(n)
        x = b.copy()
        work = a.copy()
        lu_solve_inplace(work, x)
        np.testing.assert_array_equal(x, _textbook(a, b))
        np.testing.assert_allclose(a @ x, b, rtol=0, atol=1e-10 * np.abs(a).max() * max(1.0, np.abs(x).max()))
        x2 = b.copy()
        lu_solve_inplace(a.copy(), x2, np.full(n, np.nan))  # scratch passed in: its contents never matter
        np.testing.assert_array_equal(x2, x)


def test_singular_stays_finite():
    a = np.zeros((4, 4))
    x = np.ones(4)
    lu_solve_inplace(a, x)
    assert np.isfinite(x).all()
