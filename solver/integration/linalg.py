"""Dense linear algebra of the time loop: an LU factorisation kept across Newton iterations and
time steps (numba's ``np.linalg.solve`` refactorises at every call) and the matrix-vector
product with the elastic matrix.

LAPACK's ``dgetrf`` and BLAS ``dtrsv``/``dgemv`` from SciPy's Cython bindings, called from compiled
code (no GIL): 5-6x faster than a plain compiled triple loop at N ~ 130 on this machine. They are
bound by symbol name (``llvmlite.binding.add_symbol`` + ``ExternalFunction``), not as ctypes pointers,
so the calling functions stay cacheable. The arrays are C-ordered, so LAPACK factors the
transpose, and the solves use ``trans = 'T'``.
"""

import llvmlite.binding as llvm
import numpy as np
from numba import types
from numba.extending import get_cython_function_address

from .._jit import jit

llvm.add_symbol("ehd_dgetrf", get_cython_function_address("scipy.linalg.cython_lapack", "dgetrf"))
for _name in ("dgemv", "dtrsv"):
    llvm.add_symbol(f"ehd_{_name}", get_cython_function_address("scipy.linalg.cython_blas", _name))

_p = types.voidptr
_dgetrf = types.ExternalFunction("ehd_dgetrf", types.void(_p, _p, _p, _p, _p, _p))
_dgemv = types.ExternalFunction("ehd_dgemv",
                                types.void(_p, _p, _p, _p, _p, _p, _p, _p, _p, _p, _p))
_dtrsv = types.ExternalFunction("ehd_dtrsv", types.void(_p, _p, _p, _p, _p, _p, _p, _p))


@jit
def matvec(a, x, out):
    """``out = a @ x`` (a C-ordered, square) by BLAS ``dgemv``: 2-3x faster than a compiled
    loop, and with a fixed summation order (numba's ``reassoc`` made freshly compiled and
    cache-loaded code sum differently)."""
    trans = np.empty(1, np.uint8)
    trans[0] = ord("T")  # BLAS reads the C-ordered matrix as its transpose
    n = np.empty(1, np.int32)
    n[0] = a.shape[0]
    one = np.ones(1, np.int32)
    alpha = np.ones(1)
    zero = np.zeros(1)
    _dgemv(trans.ctypes, n.ctypes, n.ctypes, alpha.ctypes, a.ctypes, n.ctypes, x.ctypes,
           one.ctypes, zero.ctypes, out.ctypes, one.ctypes)


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
    """Solve ``A x = b`` in place in ``b`` given ``lu_factor``'s output for ``A``.

    LAPACK holds the factors of ``A^T = P L U`` (C order read as Fortran order), so
    ``A = U^T L^T P^T``: two triangular solves by BLAS ``dtrsv`` (``U^T``, then the unit ``L^T``),
    then the row interchanges in reverse. This is what ``dgetrs(trans='T')`` does, in half its
    time for one right-hand side (measured 8.5 against 17.7 us at N = 125: its ``dtrsm`` path is
    slow for a single vector), and it is the time loop's most frequent call (one per Newton
    iteration)."""
    n = np.empty(1, np.int32)
    n[0] = lu.shape[0]
    one = np.ones(1, np.int32)
    codes = np.empty(4, np.uint8)  # 'U', 'L', 'T', 'N'
    codes[0], codes[1], codes[2], codes[3] = ord("U"), ord("L"), ord("T"), ord("N")
    upper, lower, trans, non_unit = codes[0:1], codes[1:2], codes[2:3], codes[3:4]
    _dtrsv(upper.ctypes, trans.ctypes, non_unit.ctypes, n.ctypes, lu.ctypes, n.ctypes, b.ctypes,
           one.ctypes)
    _dtrsv(lower.ctypes, trans.ctypes, upper.ctypes, n.ctypes, lu.ctypes, n.ctypes, b.ctypes,
           one.ctypes)  # diag = 'U': L has a unit diagonal
    for i in range(lu.shape[0] - 1, -1, -1):
        k = piv[i] - 1
        if k != i:
            t = b[i]
            b[i] = b[k]
            b[k] = t
    return b
