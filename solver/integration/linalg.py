"""Dense linear algebra of the time loop: an LU factorisation kept across Newton iterations and
time steps (numba's ``np.linalg.solve`` refactorises at every call), the matrix-vector
product with the elastic matrix and a matrix product (a rough film's contact).

LAPACK's ``dgetrf``/``dgetrs`` and BLAS ``dgemv``/``dgemm`` from SciPy's Cython bindings, called from compiled code (no GIL):
5-6x faster than a plain compiled triple loop at N ~ 130 on this machine. They are bound by
symbol name (``llvmlite.binding.add_symbol`` + ``ExternalFunction``), not as ctypes pointers,
so the calling functions stay cacheable. The arrays are C-ordered, which LAPACK reads as their
transpose: ``lu_factor`` transposes the matrix in place before factorising it, so that the solve
uses ``trans = 'N'``.
"""

import importlib.machinery
import importlib.util
import os
import sys

import llvmlite.binding as llvm
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import get_cython_function_address, intrinsic

from .._jit import copy_into, jit


def _bind(name: str, functions: tuple[str, ...]) -> None:
    """Bind ``functions`` of SciPy's Cython bindings ``scipy.linalg.<name>`` as the symbols
    ``ehd_<function>``, loading the bindings from their file, without running the package
    ``scipy.linalg`` (its ``__init__`` imports SciPy's array-API layer: about 0.1 s of every run,
    for two modules that need none of it).

    The module is in ``sys.modules`` under its name while its functions are bound (Cython
    registers it itself), and taken out again after, so that a later import of ``scipy.linalg.<name>`` is a
    plain one, which sets the attribute of ``scipy.linalg`` as usual (Cython hands it the same
    module object). Where it or its package is imported already, or its file is not found
    (another SciPy layout), numba imports it the plain way."""
    full = f"scipy.linalg.{name}"
    loaded_here = False
    if full not in sys.modules and "scipy.linalg" not in sys.modules:
        scipy_spec = importlib.util.find_spec("scipy")  # a top-level package: found, not imported
        folder = os.path.join(os.path.dirname(scipy_spec.origin), "linalg")
        for suffix in importlib.machinery.EXTENSION_SUFFIXES:
            path = os.path.join(folder, name + suffix)
            if os.path.isfile(path):
                loader = importlib.machinery.ExtensionFileLoader(full, path)
                module = importlib.util.module_from_spec(
                    importlib.util.spec_from_file_location(full, path, loader=loader))
                loader.exec_module(module)
                sys.modules.setdefault(full, module)  # where Cython did not register it
                loaded_here = True
                break
    for function in functions:
        llvm.add_symbol(f"ehd_{function}", get_cython_function_address(full, function))
    if loaded_here:
        del sys.modules[full]


_bind("cython_lapack", ("dgetrf", "dgetrs"))
_bind("cython_blas", ("dgemv", "dgemm"))

_p = types.voidptr
_dgetrf = types.ExternalFunction("ehd_dgetrf", types.void(_p, _p, _p, _p, _p, _p))
_dgetrs = types.ExternalFunction("ehd_dgetrs", types.void(_p, _p, _p, _p, _p, _p, _p, _p, _p))
_dgemv = types.ExternalFunction("ehd_dgemv",
                                types.void(_p, _p, _p, _p, _p, _p, _p, _p, _p, _p, _p))
_dgemm = types.ExternalFunction("ehd_dgemm",
                                types.void(_p, _p, _p, _p, _p, _p, _p, _p, _p, _p, _p, _p, _p))


# The arguments BLAS and LAPACK take by address. An array's ``.ctypes`` holds a reference to
# it (counted up and down at each use) and a one-entry array per scalar is an allocation: with
# five of each per call, 4364 dgemv and 2489 dgetrs per collision, they were most of numba's
# reference counting in the loop (benchmarks/refcount.md). The data pointer and a scalar in the
# caller's stack frame carry neither.
@intrinsic
def _data(typingctx, array):
    """The address of ``array``'s data (no reference counted)."""
    if not isinstance(array, types.Array):
        return None

    def codegen(context, builder, signature, args):
        ary = context.make_array(signature.args[0])(context, builder, args[0])
        return builder.bitcast(ary.data, cgutils.voidptr_t)

    return types.voidptr(array), codegen


def _cell(numba_type, llvm_type):
    """An intrinsic that stores its argument, cast to ``numba_type``, in a slot of the calling
    function's stack frame and returns the slot's address (valid until that function returns)."""

    @intrinsic
    def cell(typingctx, value):
        def codegen(context, builder, signature, args):
            slot = cgutils.alloca_once(builder, llvm_type)
            builder.store(context.cast(builder, args[0], signature.args[0], numba_type), slot)
            return builder.bitcast(slot, cgutils.voidptr_t)

        return types.voidptr(value), codegen

    return cell


_int32_cell = _cell(types.int32, ir.IntType(32))
_char_cell = _cell(types.uint8, ir.IntType(8))
_double_cell = _cell(types.float64, ir.DoubleType())


@intrinsic
def _int32_at(typingctx, address):
    """The int32 stored at ``address`` (a ``_int32_cell``'s, after LAPACK wrote it)."""

    def codegen(context, builder, signature, args):
        return builder.load(builder.bitcast(args[0], ir.IntType(32).as_pointer()))

    return types.int32(types.voidptr), codegen


# BLAS and LAPACK read a C-ordered matrix as its transpose: trans = "T" (84), or "N" (78) for a
# matrix stored transposed (ord() compiles numba's unicode code)
_TRANSPOSE, _NO_TRANSPOSE = 84, 78


@jit
def matvec(a, x, out):
    """``out = a @ x`` (a C-ordered, square) by BLAS ``dgemv``: 2-3x faster than a compiled
    loop, and with a fixed summation order (numba's ``reassoc`` made freshly compiled and
    cache-loaded code sum differently)."""
    n = _int32_cell(a.shape[0])
    one = _int32_cell(1)
    _dgemv(_char_cell(_TRANSPOSE), n, n, _double_cell(1.0), _data(a), n, _data(x), one,
           _double_cell(0.0), _data(out), one)


@jit
def matmul(a, b, out):
    """``out = a @ b`` (all C-contiguous; a (n, k), b (k, m), out (n, m), k > 0) by BLAS
    ``dgemm``, called as numba's ``a @ b`` calls it for n and m above 1 (its C-ordered product is
    the Fortran-ordered ``b^T a^T``: the same arguments, the same sums; with one row or column
    numba takes a matrix-vector product instead). numba's product compiled its own
    implementation with four array allocations, about 0.6 s of a cold compile (3 %), for one
    product in a rough film's contact (model/contact.py). Other shapes or layouts raise
    ValueError (BLAS would read and write past the arrays)."""
    if (a.shape[1] != b.shape[0] or out.shape[0] != a.shape[0] or out.shape[1] != b.shape[1]
            or not (a.flags.c_contiguous and b.flags.c_contiguous and out.flags.c_contiguous)):
        raise ValueError("matmul: the arrays' shapes or layouts do not match")
    rows, inner, cols = _int32_cell(a.shape[0]), _int32_cell(a.shape[1]), _int32_cell(b.shape[1])
    _dgemm(_char_cell(_NO_TRANSPOSE), _char_cell(_NO_TRANSPOSE), cols, rows, inner,
           _double_cell(1.0), _data(b), cols, _data(a), inner, _double_cell(0.0), _data(out), cols)


@jit
def lu_factor(a, piv):
    """Factor ``a`` (n, n, C order) in place; ``piv`` (n,) int32. False if singular. ``a`` is
    transposed in place first, so that LAPACK, which reads C order as the transpose, factors
    ``a`` itself: ``lu_solve`` then solves with ``trans = 'N'``, whose triangular solves run
    down columns (BLAS axpy), where ``'T'`` takes a dot product per row (``dot_compute``, 13 %
    of a classic collision's CPU time; benchmarks/profile.md). The transpose costs about
    4.5 us at N ~ 125 against 80-110 us for the factorisation."""
    m = a.shape[0]
    for i in range(m):
        for j in range(i + 1, m):
            a[i, j], a[j, i] = a[j, i], a[i, j]
    n = _int32_cell(m)
    info = _int32_cell(0)
    _dgetrf(n, n, _data(a), n, _data(piv), info)
    return _int32_at(info) == 0


@jit
def lu_solve(lu, piv, b):
    """Solve ``A x = b`` in place in ``b`` given ``lu_factor``'s output for ``A`` (the factors of
    ``A`` in Fortran order)."""
    _getrs(lu, piv, b, 1)
    return b


@jit
def lu_solve_rows(lu, piv, b):
    """Solve ``A x = b_r`` in place for each row ``b_r`` of ``b`` (C order, (r, N)): one LAPACK
    call (a triangular solve with r right-hand sides, BLAS level 3) instead of r."""
    _getrs(lu, piv, b, b.shape[0])
    return b


@jit
def _getrs(lu, piv, b, nrhs):
    """LAPACK's dgetrs with trans = 'N' on ``nrhs`` right-hand sides of N entries each, stored
    one after the other in ``b`` (a C-ordered (nrhs, N) array is the Fortran-ordered (N, nrhs))."""
    n = _int32_cell(lu.shape[0])
    info = _int32_cell(0)
    _dgetrs(_char_cell(_NO_TRANSPOSE), n, _int32_cell(nrhs), _data(lu), n, _data(piv), _data(b),
            n, info)


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
    lu_solve_rows(lu, piv, z[:r])
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
