"""
One collision's film: pressure and deformation profiles
=======================================================

``solver.collide`` solves one head-on collision from its two dimensionless groups, the Stokes
number ``St`` and the elasticity parameter ``eps`` (docs/model.md, "The parameters"). The result
keeps the radial profiles of the coupled phase; ``pipeline.plots.scene_plots.plot_profiles``
draws them as ``ehd run --plot`` does. Lengths are in ``x1``, pressure in ``mu a v0 / x1^2``.
"""

import matplotlib.pyplot as plt

from pipeline.plots.scene_plots import plot_profiles
from solver import collide

c = collide(10.0, 1e-2, accuracy="fast")
print(f"status {c.status}: v_r = {c.v_r:.4f}, e_wet = {c.e_wet:.4f}, h_m = {c.h_m_x1:.4f} x1")

fig, (ax_p, ax_w) = plt.subplots(1, 2, figsize=(10, 4), layout="constrained")
plot_profiles(ax_p, c, "P")
plot_profiles(ax_w, c, "W")
ax_p.set_title("film pressure")
ax_w.set_title("surface deformation")
plt.show()
