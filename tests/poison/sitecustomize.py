"""Poisoned allocation for tests/test_memory.py: on a Python started with this folder on
PYTHONPATH and ``EHD_POISON_BYTE`` set, every array numba's compiled code allocates (``np.empty``,
``np.empty_like``, the arrays behind ``np.zeros`` before their zero fill, ...) starts filled with
that byte (0xFF: float NaN and int -1; 0x7F: floats near 1.4e306), so any read of memory the code
never wrote changes its results. Run it with its own ``EHD_CACHE_DIR``: the compiled code differs
from the cached one while the solver's source hash does not.

It wraps numba's allocation helper ``numba.np.arrayobj._empty_nd_impl`` (numba 0.59-0.68), which
numba's own array constructors look up by name when they are compiled."""

import os

_byte = os.environ.get("EHD_POISON_BYTE")
if _byte:
    import numba.np.arrayobj as _arrayobj
    from numba.core import cgutils as _cgutils

    _allocate = _arrayobj._empty_nd_impl
    _value = int(_byte, 0)

    def _poisoned(context, builder, arrtype, shapes):
        ary = _allocate(context, builder, arrtype, shapes)
        _cgutils.memset(builder, ary.data, builder.mul(ary.itemsize, ary.nitems), _value)
        return ary

    _arrayobj._empty_nd_impl = _poisoned
