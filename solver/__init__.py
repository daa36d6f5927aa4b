"""ehd-collision solver core: one elastohydrodynamic collision of two elastic spheres.

Pure numerics (numpy, scipy.special, numba); no I/O. Public API::

    from solver import Physics, collide
    c = collide(Physics(St=5.0, eps=0.01), accuracy="standard")   # or collide(5.0, 0.01)
    c.v_r, c.h_m_x1, c.x_e_x1, c.to_json(), c.to_xarray()

The model is written down in docs/model.md; the observables, status codes and series columns are
declared once in ``solver.observables``.
"""

from .collision import collide, hertz_overlap
from .observables import MODEL_CODES, OBSERVABLES, STATUS, STATUS_CODES
from .physics import Physics
from .result import JSON_KEYS, SOLVER_VERSION, Collision
from .settings import PRESETS, Numerics

__all__ = ["collide", "Collision", "Physics", "SOLVER_VERSION", "STATUS", "STATUS_CODES",
           "MODEL_CODES", "OBSERVABLES", "JSON_KEYS", "PRESETS", "Numerics", "hertz_overlap"]
