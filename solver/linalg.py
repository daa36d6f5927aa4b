"""Dense LU with partial pivoting, compiled, so a factorisation can be reused across Newton
iterations and time steps (numba's ``np.linalg.solve`` refactorises at every call)."""

import numpy as np

from ._jit import jit


@jit
def lu_factor(a, piv):
    """Factor ``a`` (n, n) in place into unit-lower L and upper U with row pivots ``piv`` (n,).

    Returns False when a zero pivot makes the matrix singular."""
    n = a.shape[0]
    for k in range(n):
        p = k
        big = abs(a[k, k])
        for i in range(k + 1, n):
            if abs(a[i, k]) > big:
                big = abs(a[i, k])
                p = i
        piv[k] = p
        if big == 0.0:
            return False
        if p != k:
            for j in range(n):
                t = a[k, j]
                a[k, j] = a[p, j]
                a[p, j] = t
        inv = 1.0 / a[k, k]
        for i in range(k + 1, n):
            a[i, k] *= inv
        for i in range(k + 1, n):
            f = a[i, k]
            if f != 0.0:
                for j in range(k + 1, n):
                    a[i, j] -= f * a[k, j]
    return True


@jit
def lu_solve(lu, piv, b):
    """Solve ``A x = b`` in place in ``b`` given ``lu_factor``'s output."""
    n = lu.shape[0]
    for k in range(n):
        p = piv[k]
        if p != k:
            t = b[k]
            b[k] = b[p]
            b[p] = t
    for i in range(n):
        acc = b[i]
        for j in range(i):
            acc -= lu[i, j] * b[j]
        b[i] = acc
    for i in range(n - 1, -1, -1):
        acc = b[i]
        for j in range(i + 1, n):
            acc -= lu[i, j] * b[j]
        b[i] = acc / lu[i, i]
    return b
