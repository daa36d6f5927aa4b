"""
Wet restitution against the Stokes number
==========================================

The wet coefficient of restitution ``e_wet`` of a few collisions at one elasticity parameter,
``fast`` preset (a few milliseconds each), next to the form of the experiments' correlation,
``e/e_dry = exp(-35/St_L)``, drawn with ``St_L = St`` (the correlation's Stokes number counts
the fluid's added mass; benchmarks/experiments.md compares on the experiments' own conditions).
Below the sticking threshold the spheres do not rebound (``e_wet = 0``).
"""

import matplotlib.pyplot as plt
import numpy as np

from solver import collide

eps = 1e-4
stokes = np.geomspace(5.0, 1000.0, 12)
e_wet = [collide(float(St), eps, accuracy="fast").e_wet for St in stokes]

fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
ax.semilogx(stokes, e_wet, "o-", label=rf"model, $\epsilon$ = {eps:g}")
ax.semilogx(stokes, np.exp(-35.0 / stokes), "k--", label="exp(-35/St)")
ax.set_xlabel("Stokes number St")
ax.set_ylabel("wet restitution e_wet")
ax.set_ylim(0.0, 1.0)
ax.legend()
plt.show()
