"""e_wet(St) at eps = 1e-4, 1e-6, 1e-8 on a dense St grid (standard accuracy, direct solves),
saved to benchmarks/e_wet_curves.json for the experiments figure (benchmarks/e_wet_figure.py).

    python benchmarks/e_wet_curves.py     (~5 min on one core)
"""

from pathlib import Path

import numpy as np

import harness
from pipeline import environment  # noqa: F401  (single-threaded BLAS)
from solver import SOLVER_VERSION, collide

EPS = (1e-4, 1e-6, 1e-8)
STOKES = np.geomspace(8.0, 1000.0, 25)


def main():
    load_start = harness.load_now()
    out = {"solver_version": SOLVER_VERSION, "accuracy": "standard", "St": STOKES.tolist(),
           "e_wet": {}}
    for eps in EPS:
        values = []
        for st in STOKES:
            c = collide(float(st), eps, accuracy="standard", save_profiles=False)
            values.append(c.e_wet if c.ok else None)
        out["e_wet"][f"{eps:g}"] = values
        print(eps, [round(v, 4) if v is not None else None for v in values], flush=True)
    path = Path(__file__).with_name("e_wet_curves.json")
    harness.write_json(path, out, load_start)
    print("wrote", path)


if __name__ == "__main__":
    main()
