"""ehd-collision solver core: one elastohydrodynamic collision of two elastic spheres.

Pure numerics (numpy, numba, SciPy); no I/O. Public API::

    from solver import Physics, collide
    c = collide(Physics(St=5.0, eps=0.01), accuracy="standard")   # or collide(5.0, 0.01)
    c.v_r, c.h_m_x1, c.x_e_x1, c.to_json(), c.to_xarray()

Run it with one BLAS thread (``OPENBLAS_NUM_THREADS=1`` before numpy is imported; ``ehd`` and
``import pipeline`` set it): threaded BLAS is slower for its matrices (docs/solver.md).

The model is written down in docs/model.md; the observables, status codes and series columns are
declared once in ``solver.observables``.
"""

import importlib

# name -> the submodule that defines it. Loaded on first use (PEP 562): ``import solver`` or
# ``from solver.observables import ...`` (the registry, for command-line parsing and stores) does
# not compile or even import numba; ``solver.collide`` does.
_EXPORTS = {"collide": "collision", "hertz_overlap": "collision",
            "MODEL_CODES": "observables", "OBSERVABLES": "observables", "STATUS": "observables",
            "STATUS_CODES": "observables", "Physics": "physics", "JSON_KEYS": "result",
            "SOLVER_VERSION": "result", "Collision": "result", "PRESETS": "settings",
            "Numerics": "settings"}

__all__ = ["collide", "Collision", "Physics", "SOLVER_VERSION", "STATUS", "STATUS_CODES",
           "MODEL_CODES", "OBSERVABLES", "JSON_KEYS", "PRESETS", "Numerics", "hertz_overlap"]


def __getattr__(name):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'solver' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted({*globals(), *__all__})
