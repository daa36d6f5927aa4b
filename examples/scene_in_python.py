"""A scene in physical units from Python: the same as ``ehd scene``, then a sweep over the
impact speed, and the sticking threshold of the materials.

    python examples/scene_in_python.py        (from the clone, or from a folder made by
                                               ``ehd examples DIR``; a few seconds once compiled)

Every quantity is a number in SI units or a string with its unit ("50 um", "10 cm/s").
"""

import dataclasses
from pathlib import Path

from pipeline.scenes.commands import format_report, load_scene
from pipeline.scenes.run import run_scene
from pipeline.scenes.threshold import format_threshold, sticking_threshold

HERE = Path(__file__).resolve().parent

# 1. A scene from a file, with a field overridden (as the flags of ehd scene do) ...
scene = load_scene(str(HERE / "glass_beads_water.toml"), {"v0": "20 cm/s"})
# ... or from the fields alone (named materials: ehd scene --list-materials)
steel_in_oil = load_scene(flags={"material1": "steel", "radius1": "1 mm", "wall2": True,
                                 "material2": "glass", "fluid": "mineral_oil", "v0": "0.5 m/s"})

# 2. Solve: the same checks, automatic switches and report as the command line
result = run_scene(scene, accuracy="standard")
print(format_report(result.to_dict()))
d = result.to_dict()  # the keys of ehd scene --json (docs/scenes.md)
print(f"\ne_wet = {d['e_wet']:.4f}, closest approach {d['closest_approach_nm']:.3g} nm, "
      f"peak pressure {d['peak_pressure_Pa'] / 1e6:.4g} MPa")
for w in result.warnings:  # validity warnings: which premise, the number, the threshold
    print(f"warning [{w.check}]: {w.value:.3g} against {w.threshold:.3g}")

# 3. Your own sweep: the impact speed from 5 to 50 cm/s (eps and St move with it)
for v0 in (0.05, 0.1, 0.2, 0.5):
    r = run_scene(dataclasses.replace(scene, v0=v0), accuracy="fast")
    print(f"v0 = {v0:5.2f} m/s: St = {r.scene.stokes:7.3g}, eps = {r.scene.eps:.3g}, "
          f"e_wet = {r.collision.e_wet:.3f}")

# 4. Below which speed do these beads stick?
print(format_threshold(sticking_threshold(scene, "v0", accuracy="fast")))

# 5. The steel ball on a glass wall in mineral oil: the oil's pressure-dependent viscosity is
#    switched on by itself (the viscosity line of the report says why)
r = run_scene(steel_in_oil, accuracy="fast")
print(f"\nsteel in oil: {r.viscosity_reason[:100]}...")
