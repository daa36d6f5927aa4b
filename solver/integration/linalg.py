"""Dense linear algebra of the time loop: an LU factorisation kept across Newton iterations and
time steps (numba's ``np.linalg.solve`` refactorises at every call) and the matrix-vector
product with the elastic matrix.

LAPACK's ``dgetrf``/``dgetrs`` and BLAS ``dgemv`` from SciPy's Cython bindings, called from compiled code (no GIL):
5-6x faster than a plain compiled triple loop at N ~ 130 on this machine. They are bound by
symbol name (``llvmlite.binding.add_symbol`` + ``ExternalFunction``), not as ctypes pointers,
so the calling functions stay cacheable. The arrays are C-ordered, so LAPACK factors the
transpose, and the solve uses ``trans = 'T'``.
"""

import llvmlite.binding as llvm
import numpy as np
from numba import types
from numba.extending import get_cython_function_address

from .._jit import copy_into, jit

for _name in ("dgetrf", "dgetrs"):
    llvm.add_symbol(f"ehd_{_name}", get_cython_function_address("scipy.linalg.cython_lapack", _name))
llvm.add_symbol("ehd_dgemv", get_cython_function_address("scipy.linalg.cython_blas", "dgemv"))

_p = types.voidptr
_dgetrf = types.ExternalFunction("ehd_dgetrf", types.void(_p, _p, _p, _p, _p, _p))
_dgetrs = types.ExternalFunction("ehd_dgetrs", types.void(_p, _p, _p, _p, _p, _p, _p, _p, _p))
_dgemv = types.ExternalFunction("ehd_dgemv",
                                types.void(_p, _p, _p, _p, _p, _p, _p, _p, _p, _p, _p))


@jit
def matvec(a, x, out):
    """``out = a @ x`` (a C-ordered, square) by BLAS ``dgemv``: 2-3x faster than a compiled
    loop, and with a fixed summation order (numba's ``reassoc`` made freshly compiled and
    cache-loaded code sum differently)."""
    trans = np.empty(1, np.uint8)
    trans[0] = 84  # ord("T") (ord compiles numba's unicode code); BLAS reads the C-ordered matrix as its transpose
    n = np.empty(1, np.int32)
    n[0] = a.shape[0]
    one = np.ones(1, np.int32)
    alpha = np.ones(1)
    beta = np.zeros(1)
    _dgemv(trans.ctypes, n.ctypes, n.ctypes, alpha.ctypes, a.ctypes, n.ctypes, x.ctypes,
           one.ctypes, beta.ctypes, out.ctypes, one.ctypes)


@jit
def lu_factor(a, piv):
    """Factor ``a`` (n, n, C order) in place; ``piv`` (n,) int32. False if singular."""
    n = np.empty(1, np.int32)
    n[0] = a.shape[0]
    info = np.zeros(1, np.int32)
    _dgetrf(n.ctypes, n.ctypes, a.ctypes, n.ctypes, piv.ctypes, info.ctypes)
    return info[0] == 0


@jit
def lu_solve(lu, piv, b):
    """Solve ``A x = b`` in place in ``b`` given ``lu_factor``'s output for ``A``."""
    trans = np.empty(1, np.uint8)
    trans[0] = 84  # ord("T"), as in matvec; LAPACK holds the factors of A^T (C order read as Fortran order)
    n = np.empty(1, np.int32)
    n[0] = lu.shape[0]
    one = np.ones(1, np.int32)
    info = np.zeros(1, np.int32)
    _dgetrs(trans.ctypes, n.ctypes, one.ctypes, lu.ctypes, n.ctypes, piv.ctypes, b.ctypes,
            n.ctypes, info.ctypes)
    return b


# The largest number of slots whose rows and columns a low-rank update replaces (rank 2 each);
# beyond it the matrix is factorised afresh.
MAX_SLOTS = 8


@jit
def lowrank_prepare(lu, piv, base, fresh, slots, k, u, v, z, cap, cpiv):
    """Prepare solves with ``A'``: the factorised matrix ``A`` (``lu``, ``piv``; ``base`` its
    copy before factorising) with the rows and the columns of ``slots[:k]`` replaced by those of
    ``fresh``. ``A' = A + U V^T`` of rank ``2k`` (a row replacement ``e_i r_i^T``, a column
    replacement ``c_i e_i^T`` without the rows already replaced), solved by the
    Sherman-Morrison-Woodbury formula: ``Z = A^-1 U`` (rows of ``z``) and the capacitance matrix
    ``C = I + V^T Z`` (factorised into ``cap``, ``cpiv``) once here, then each solve costs one solve
    with ``A`` and ``O(k N)`` (``lowrank_solve``) instead of a factorisation, ``O(N^3)``. ``u``,
    ``v``, ``z`` are (2 MAX_SLOTS, N). False if ``C`` is singular."""
    n = base.shape[0]
    r = 2 * k
    for a in range(k):
        i = slots[a]
        for j in range(n):
            u[a, j] = 0.0
            v[a, j] = fresh[i, j] - base[i, j]
            u[k + a, j] = fresh[j, i] - base[j, i]
            v[k + a, j] = 0.0
        u[a, i] = 1.0
        v[k + a, i] = 1.0
    for a in range(k):  # entries in replaced rows belong to the row replacement
        for b in range(k):
            u[k + a, slots[b]] = 0.0
    for a in range(r):
        copy_into(z[a], u[a])
        lu_solve(lu, piv, z[a])
    c = cap[: r * r].reshape((r, r))
    for a in range(r):
        for b in range(r):
            dot = 0.0
            for j in range(n):
                dot += v[a, j] * z[b, j]
            c[a, b] = dot + (1.0 if a == b else 0.0)
    return lu_factor(c, cpiv[:r])


@jit
def lowrank_solve(lu, piv, k, v, z, cap, cpiv, b, t):
    """Solve ``A' x = b`` in place in ``b`` (``lowrank_prepare``; ``k = 0``: ``A`` itself). ``t``
    is work space of 2 MAX_SLOTS entries."""
    lu_solve(lu, piv, b)
    if k == 0:
        return b
    r = 2 * k
    n = b.size
    for a in range(r):
        dot = 0.0
        for j in range(n):
            dot += v[a, j] * b[j]
        t[a] = dot
    lu_solve(cap[: r * r].reshape((r, r)), cpiv[:r], t[:r])
    for a in range(r):
        ta = t[a]
        for j in range(n):
            b[j] -= z[a, j] * ta
    return b
