"""ehd-collision solver core: one elastohydrodynamic collision of two elastic spheres.

Pure numerics (numpy, scipy.special, numba); no I/O. Public API::

    from solver import collide
    c = collide(5.0, 0.01, accuracy="standard")
    c.v_r, c.h_m_x1, c.x_e_x1, c.to_json(), c.to_xarray()
"""

from .collision import JSON_KEYS, SOLVER_VERSION, STATUS, Collision, collide, hertz_overlap
from .settings import PRESETS, Numerics

__all__ = ["collide", "Collision", "SOLVER_VERSION", "STATUS", "JSON_KEYS", "PRESETS", "Numerics",
           "hertz_overlap"]
