"""The scenes of tests/test_memory.py, run in one process: ``python scenes.py OUT.json`` writes
every observable of each (exact, as ``float.hex``), its status and message.

Rough surfaces over St 1-30 x eps 1e-2-1e-8 (the 108 scenes in which a rough film coming to rest
left its cavity columns unwritten: 35 of them changed under poisoned allocation), and each piece
of physics at two St and two presets, the profiles saved on some."""

import json
import sys

import numpy as np

ROUGH = dict(roughness=1.0, asperity_stiffness=2.0, e_dry=0.8)
PIECES = ({}, dict(Pi=1e-3, cavitation="jfo"), dict(Pi=1e-2, cavitation="reynolds"),
          dict(beta=1.0, viscosity_law="barus"),
          dict(beta=1.0, viscosity_law="barus", density_law="dowson-higginson"),
          dict(beta=0.5, viscosity_law="roelands"), ROUGH, dict(ROUGH, Pi=1e-3, cavitation="jfo"),
          dict(roughness=0.3, asperity_stiffness=1e4, e_dry=0.97, Pi=1e-2,
               cavitation="reynolds"))


def scenes():
    for st in np.geomspace(1.0, 30.0, 12):
        for eps in np.geomspace(1e-2, 1e-8, 9):
            yield dict(St=float(st), eps=float(eps), **ROUGH), "standard", False
    for st in (3.0, 40.0):
        for k, piece in enumerate(PIECES):
            yield dict(St=st, eps=1e-4, **piece), ("fast", "fine")[k % 2], k % 3 == 0


def main(out):
    from solver import Physics, collide
    from solver.observables import OBSERVABLES

    rows = []
    for fields, accuracy, profiles in scenes():
        c = collide(Physics(**fields), accuracy=accuracy, save_profiles=profiles)
        row = {o.name: getattr(c, o.name) for o in OBSERVABLES if o.name != "wall_s"}
        row = {k: v.hex() if isinstance(v, float) else v for k, v in row.items()}
        row.update(status=c.status, message=c.message)
        if profiles:
            row["profiles"] = [float(np.nansum(a)).hex() for a in (c.pressure, c.deformation)]
        rows.append({"scene": fields, "accuracy": accuracy, "result": row})
    with open(out, "w") as f:
        json.dump(rows, f)


if __name__ == "__main__":
    main(sys.argv[1])
