"""The exported DEM snippets in the real programs: LIGGGHTS 3.8.0 and YADE 2023.02a (Debian).

Each snippet is pasted verbatim into a geometry-only input kept in tests/dem/ (boxes, bodies,
speeds, integrator, time step ``ehd_dt_max`` as the snippet states it), and head-on collisions
run at every St of the export, sticking to rebounding, in one program run per export and
geometry (a few seconds each). Asserted: the realised e lies within the JSON's stated error
(``realised_max_error`` of that code, every row) + 0.01 of the model's e the export realises
(``e_realised``: ``e_far`` for a dry DEM code, the default; ``e_wet`` with ``--for cfd-dem``),
each collision launched at the speed the law is calibrated against (``speed_column``: for dry
the approach speed at x_ref), for store exports (dry: a sphere on a wall, where a store reads
e_far; cfd-dem: two spheres) and scene exports (dry: two spheres, a sphere on a wall; cfd-dem:
unequal spheres, which have no e_far yet). For LIGGGHTS also the replica's own prediction row by
row, which checks the stated time step.

`make test-dem` installs the packages (apt-get, as root) and runs this file; where a program is
missing the tests skip with the reason (never pass silently).
"""

import json
import math
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from pipeline.cli import main
from pipeline.dem import liggghts
from pipeline.dem.export import read_csv

HERE = Path(__file__).parent / "dem"
PAIR_SCENE = "examples/glass_beads_water.toml"
WALL_SCENE = str(HERE / "glass_bead_glass_wall_water.toml")
UNEQUAL_SCENE = str(HERE / "glass_bead_steel_ball_water.toml")
# The e the programs realise may differ from what the JSON states by the program's own
# numerics: LIGGGHTS' fixed time step at tc/200 (pipeline/dem/liggghts.py: 0.004 measured), YADE's
# Newton iteration for the dashpot (stops at 1 % relative) and its time step. 0.01 is the margin
# the issue (18) asks for on top of the stated error.
MARGIN = 0.01
# A collision that barely rebounds (e ~ 1e-4) ends with a gap of round-off size: positions to
# 1e-16 relative, so a gap above -1e-12 radii counts as separated (with a separating velocity).
SEPARATED = 1e-12
CONTACT_STEPS = 60 * liggghts.STEPS_PER_CONTACT  # 60 contact times: separation even when stuck


def _needs(name):
    """Skip (before the fixtures' sweeps and solves) where the program is not installed."""
    return pytest.mark.skipif(shutil.which(name) is None, reason=(
        f"{name} not installed: `make test-dem` installs the Debian package {name} "
        "(apt-get install -y, as root)"))


needs_liggghts, needs_yade = _needs("liggghts"), _needs("yade")


def _program(name):
    return shutil.which(name)


def _run(cmd, cwd, timeout=120):
    proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, errors="replace",
                          timeout=timeout)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, f"{cmd[0]} failed ({proc.returncode}):\n{out[-3000:]}"
    assert "ERROR" not in proc.stdout, out[-3000:]
    return out


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    from pipeline.sweeps.config import parse_sweep
    from pipeline.sweeps.run import run_sweep

    tmp = tmp_path_factory.mktemp("dem_store")
    # St across the threshold (St_c ~ 12 at eps 1e-4) up to the tail, one eps group
    text = ('name = "dem-programs"\nstore = "x.zarr"\n[grid]\n'
            'St = [6.0, 10.0, 12.5, 15.0, 20.0, 30.0, 50.0, 100.0, 200.0]\neps = [1e-4]\n'
            '[numerics]\naccuracy = "fast"\n')
    sweep = parse_sweep(text).with_store(tmp / "s.zarr")
    run_sweep(sweep, runner="serial", progress=None)
    return sweep.store


@pytest.fixture(scope="module")
def store_export(store, tmp_path_factory):
    out = tmp_path_factory.mktemp("dem_store_dry")
    assert main(["export-dem", str(store), "--out", str(out)]) == 0  # --for dry
    return out


@pytest.fixture(scope="module")
def store_export_cfd(store, tmp_path_factory):
    out = tmp_path_factory.mktemp("dem_store_cfd")
    assert main(["export-dem", str(store), "--for", "cfd-dem", "--out", str(out)]) == 0
    return out


def _scene_export(tmp_path_factory, scene, name, *flags):
    out = tmp_path_factory.mktemp(name)
    assert main(["export-dem", scene, "--accuracy", "fast", "--n", "9", "--out", str(out),
                 *flags]) == 0
    return out


@pytest.fixture(scope="module")
def pair_export(tmp_path_factory):
    return _scene_export(tmp_path_factory, PAIR_SCENE, "dem_pair")


@pytest.fixture(scope="module")
def wall_export(tmp_path_factory):
    return _scene_export(tmp_path_factory, WALL_SCENE, "dem_wall")


@pytest.fixture(scope="module")
def unequal_export(tmp_path_factory):
    # no e_far for unequal spheres yet (export-dem refuses --for dry on them: test_dem.py)
    return _scene_export(tmp_path_factory, UNEQUAL_SCENE, "dem_unequal", "--for", "cfd-dem")


def _collisions(out):
    """(rows, group settings, placeholders or None) of an export with one group."""
    doc = json.loads((out / "restitution.json").read_text())
    (settings,) = doc["groups"].values()
    return read_csv(out / "restitution.csv"), settings, doc.get("placeholders")


def _bodies(rows, placeholders):
    """Radii and densities of bodies 1 and 2, and the fluid viscosity: the scene's, or for a
    store the snippet's example values (what it runs with as pasted)."""
    if placeholders:
        p = placeholders
        return p["radius"], p["radius"], p["density"], p["density"], p["viscosity"]
    r = rows[0]
    r2 = r["radius2_m"] if r["radius2_m"] != "" else r["radius1_m"]
    rho2 = r["density2_kg_m3"] if r["density2_kg_m3"] != "" else r["density1_kg_m3"]
    return r["radius1_m"], r2, r["density1_kg_m3"], rho2, r["viscosity_Pa_s"]


def _contact_stokes(rows, settings):
    """Our St at the speed the law sees at contact (the JSON's ``speed_over_v0_column``)."""
    ratio = settings["realises"]["speed_over_v0_column"]
    return [r["St"] * (1.0 if ratio is None else r[ratio]) for r in rows]


def _speeds(rows, settings, geometry, placeholders):
    """Impact speeds: the JSON's ``speed_column`` (a scene) or, for a store, the speeds giving
    each row's contact St (ours = LIGGGHTS') with the bodies of ``_bodies``."""
    if not placeholders:
        return [r[settings["realises"]["speed_column"]] for r in rows]
    a1, a2, rho1, rho2, mu = _bodies(rows, placeholders)
    m1, m2 = (4 / 3 * math.pi * a**3 * rho for a, rho in ((a1, rho1), (a2, rho2)))
    meff, reff = (m1, a1) if geometry == "sphere-wall" else (m1 * m2 / (m1 + m2),
                                                              a1 * a2 / (a1 + a2))
    return [st * 6 * math.pi * mu * reff**2 / meff for st in _contact_stokes(rows, settings)]


def _check(rows, settings, realised, stated, name, extra=None):
    e = np.array([r[settings["realises"]["e_realised"]] for r in rows])
    realised = np.asarray(realised)
    err = np.abs(realised - e)
    table = "\n".join(f"  St {r['St']:8.3f}  model {m:.4f}  {name} {x:.4f}" +
                      (f"  replica {extra[k]:.4f}" if extra is not None else "")
                      for k, (r, m, x) in enumerate(zip(rows, e, realised)))
    assert np.all(err <= stated + MARGIN), f"{name}: stated error {stated:.4f}\n{table}"
    return err


# ---- LIGGGHTS ------------------------------------------------------------------------------

def _liggghts_run(out, geometry, tmp_path, edit=lambda text: text):
    """Run the export's collisions in LIGGGHTS, the snippet pasted as ``edit`` leaves it.
    Returns ``(rows, group settings, realised e per row)``."""
    exe = _program("liggghts")
    rows, s, placeholders = _collisions(out)
    lig = s["liggghts"]
    (snippet_file,) = [p for p in out.glob("liggghts_*.in") if not p.name.endswith("_wall.in")]
    snippet = edit(snippet_file.read_text())
    a1, a2, rho1, rho2, _ = _bodies(rows, placeholders)
    speeds = _speeds(rows, s, geometry, placeholders)
    ntypes = len(lig["atom_types"])
    gap = 1e-3 * a1
    pitch = 4 * (a1 + a2)
    atoms, prints, n = [], [], 0
    for k, v in enumerate(speeds):
        x = k * pitch
        if geometry == "sphere-wall":
            n += 1
            atoms += [f"create_atoms 1 single {x:.9g} 0 {a1 + gap:.9g} units box",
                      f"set atom {n} diameter {2 * a1:.9g} density {rho1:.9g}",
                      f"group ehd_g{n} id {n}", f"velocity ehd_g{n} set 0 0 {-v:.9g} units box"]
            prints += [f"variable ehd_v{n} equal vz[{n}]", f"variable ehd_z{n} equal z[{n}]",
                       f'print "EHD_RESULT {k} ${{ehd_v{n}}} ${{ehd_z{n}}}"']
        else:
            t2 = 2 if ntypes == 2 else 1
            n1, n2 = n + 1, n + 2
            n += 2
            atoms += [f"create_atoms 1 single {x:.9g} 0 {-a1 - gap / 2:.9g} units box",
                      f"create_atoms {t2} single {x:.9g} 0 {a2 + gap / 2:.9g} units box",
                      f"set atom {n1} diameter {2 * a1:.9g} density {rho1:.9g}",
                      f"set atom {n2} diameter {2 * a2:.9g} density {rho2:.9g}",
                      f"group ehd_g{n1} id {n1}", f"group ehd_g{n2} id {n2}",
                      f"velocity ehd_g{n1} set 0 0 {v / 2:.9g} units box",
                      f"velocity ehd_g{n2} set 0 0 {-v / 2:.9g} units box"]
            prints += [f"variable ehd_v{n1} equal vz[{n1}]", f"variable ehd_v{n2} equal vz[{n2}]",
                       f"variable ehd_z{n1} equal z[{n1}]", f"variable ehd_z{n2} equal z[{n2}]",
                       f'print "EHD_RESULT {k} ${{ehd_v{n1}}} ${{ehd_v{n2}}} ${{ehd_z{n1}}} '
                       f'${{ehd_z{n2}}}"']
    template = "liggghts_wall.in" if geometry == "sphere-wall" else "liggghts_pair.in"
    text = (HERE / template).read_text()
    wall_text = ""
    if geometry == "sphere-wall":
        (wall_file,) = out.glob("liggghts_*_wall.in")
        wall_text = wall_file.read_text()
    size = 4 * max(a1, a2)
    tgap = gap / min(speeds)
    for key, val in {"@SNIPPET@": snippet, "@WALL@": wall_text, "@ATOMS@": "\n".join(atoms),
                     "@PRINTS@": "\n".join(prints), "@NTYPES@": str(ntypes),
                     "@XLO@": f"{-pitch:.9g}", "@XHI@": f"{pitch * len(speeds):.9g}",
                     "@LLO@": f"{-size:.9g}", "@LHI@": f"{size:.9g}", "@ZLO@": f"{-a1:.9g}",
                     "@SKIN@": f"{0.1 * a1:.9g}",
                     "@DURATION@": f"({tgap:.9g}+{CONTACT_STEPS}*${{ehd_dt_max}})"}.items():
        text = text.replace(key, val)
    (tmp_path / "in.ehd").write_text(text)
    log = _run([exe, "-in", "in.ehd", "-log", "none", "-echo", "none"], tmp_path)
    realised = []
    for k, v in enumerate(speeds):
        m = re.search(rf"^EHD_RESULT {k} (.*)$", log, re.M)
        assert m, log[-2000:]
        vals = [float(x) for x in m.group(1).split()]
        if geometry == "sphere-wall":
            vz, z = vals
            assert z - a1 >= -SEPARATED * a1 and vz >= 0, "still in contact at the end"
            realised.append(vz / v)
        else:
            v1, v2, z1, z2 = vals
            assert z2 - z1 - a1 - a2 >= -SEPARATED * a1 and v2 >= v1, "still in contact"
            realised.append((v2 - v1) / v)
    return rows, s, realised


def _liggghts(out, geometry, tmp_path):
    rows, s, realised = _liggghts_run(out, geometry, tmp_path)
    lig = s["liggghts"]
    replica = liggghts.replica_many(_contact_stokes(rows, s), lig["MaximumRestitution"],
                                    lig["CriticalStokes"])
    _check(rows, s, realised, lig["realised_max_error"], "LIGGGHTS", replica)
    # the stated time step: LIGGGHTS realises its own law as the replica predicts it
    assert np.max(np.abs(np.array(realised) - replica)) < MARGIN
    return realised


@needs_liggghts
def test_liggghts_store_export_two_spheres(store_export_cfd, tmp_path):
    _liggghts(store_export_cfd, "sphere-sphere", tmp_path)


@needs_liggghts
def test_liggghts_store_export_sphere_on_wall(store_export, tmp_path):
    _liggghts(store_export, "sphere-wall", tmp_path)


@needs_liggghts
def test_liggghts_scene_export_two_spheres(pair_export, tmp_path):
    assert not list(pair_export.glob("liggghts_*_wall.in"))  # no wall for two spheres
    assert not list(pair_export.glob("openfoam_*"))  # a patch (wall) model
    _liggghts(pair_export, "sphere-sphere", tmp_path)


@needs_liggghts
def test_liggghts_scene_export_sphere_on_wall(wall_export, tmp_path):
    _liggghts(wall_export, "sphere-wall", tmp_path)


@needs_liggghts
def test_liggghts_scene_export_unequal_spheres(unequal_export, tmp_path):
    _liggghts(unequal_export, "sphere-sphere", tmp_path)


@needs_liggghts
def test_liggghts_limit_force_makes_sticking_collisions_rebound(pair_export, tmp_path):
    # why the snippet warns against limitForce (which LIGGGHTS' docs recommend): the same
    # export with 'limitForce on' added rebounds where the model (and the law without it) sticks
    rows, s, realised = _liggghts_run(pair_export, "sphere-sphere", tmp_path, edit=lambda t: (
        t.replace("viscous on", "viscous on limitForce on")))
    stuck = [k for k, r in enumerate(rows) if r[s["realises"]["e_realised"]] == 0.0]
    assert stuck, "the export has no sticking row"
    # 0.1: ten times the margin on the stated error, below the e 0.13-0.2 the replica gives with
    # limitForce at these St (tests/test_dem.py), far above the 0 it gives without
    assert min(realised[k] for k in stuck) > s["liggghts"]["realised_max_error"] + MARGIN
    assert max(realised[k] for k in stuck) > 0.1


# ---- YADE ----------------------------------------------------------------------------------

def _yade(out, geometry, tmp_path, edit=lambda text: text, check=True):
    """Run the export's collisions in YADE (the script as ``edit`` leaves it) and, ``check``,
    assert the realised e; returns the realised e per row."""
    exe = _program("yade")
    rows, s, placeholders = _collisions(out)
    (snippet_file,) = out.glob("yade_*.py")
    snippet = snippet_file.read_text()
    block1, _, block2 = snippet.partition("# ---- BLOCK 2")
    if block2:
        block2 = "# ---- BLOCK 2" + block2
    a1, a2, *_ = _bodies(rows, placeholders)
    speeds = _speeds(rows, s, geometry, placeholders)
    text = (HERE / "yade_collisions.py").read_text()
    for key, val in {"@GEOMETRY@": geometry, "@SPEEDS@": ", ".join(f"{v:.12g}" for v in speeds),
                     "@RADIUS2@": "None" if a2 == a1 else f"{a2:.12g}",
                     "@DURATION@": f"{0.05 * a1 / min(speeds):.9g} + {CONTACT_STEPS} * ehd_dt_max",
                     "@BLOCK1@": block1, "@BLOCK2@": block2}.items():
        text = text.replace(key, val)
    (tmp_path / "collide.py").write_text(edit(text))
    log = _run([exe, "-n", "-x", "collide.py"], tmp_path, timeout=300)
    results = [line.split()[1:] for line in log.splitlines() if line.startswith("EHD_RESULT")]
    assert len(results) == len(rows), log[-2000:]
    assert all(float(g) >= -SEPARATED * a1 for _, _, g in results), "still in contact"
    realised = [float(e) for _, e, _ in results]
    if check:
        _check(rows, s, realised, s["yade"]["realised_max_error"], "YADE")
    return realised


# the wall as two facets covering the plane z = 0 (what geom.facetBox and meshes make)
FACET_WALL = ("L = 1e3 * r1 * len(SPEEDS)\n"
              "for corners in (((-L, -L, 0), (L, -L, 0), (L, L, 0)), "
              "((-L, -L, 0), (L, L, 0), (-L, L, 0))):\n"
              "    O.bodies.append(facet(corners, material=ehd_wall_mat))\n")


def _facet_walls(text):
    """The test script with the wall as facets (and their contact geometry engines)."""
    wall = "    O.bodies.append(wall(0.0, axis=2, sense=1, material=ehd_wall_mat))\n"
    assert wall in text
    text = text.replace(wall, "    pass\n" + FACET_WALL)
    return (text.replace("Bo1_Wall_Aabb()]", "Bo1_Wall_Aabb(), Bo1_Facet_Aabb()]")
            .replace("Ig2_Wall_Sphere_ScGeom()]", "Ig2_Wall_Sphere_ScGeom(), Ig2_Facet_Sphere_ScGeom()]"))


@needs_yade
def test_yade_store_export_two_spheres(store_export_cfd, tmp_path):
    _yade(store_export_cfd, "sphere-sphere", tmp_path)


@needs_yade
def test_yade_store_export_sphere_on_wall(store_export, tmp_path):
    _yade(store_export, "sphere-wall", tmp_path)


@needs_yade
def test_yade_scene_export_two_spheres(pair_export, tmp_path):
    _yade(pair_export, "sphere-sphere", tmp_path)


@needs_yade
def test_yade_scene_export_sphere_on_wall(wall_export, tmp_path):
    _yade(wall_export, "sphere-wall", tmp_path)


@needs_yade
def test_yade_scene_export_unequal_spheres(unequal_export, tmp_path):
    _yade(unequal_export, "sphere-sphere", tmp_path)


@needs_yade
def test_yade_facet_walls_realise_too_high_an_e_and_the_snippet_stops_them(wall_export,
                                                                            tmp_path):
    # why the snippet states utils.wall only: the same collisions against facets (the guard in
    # block 2 taken out) rebound above the model's e by more than the stated error + margin
    rows, s, _ = _collisions(wall_export)
    guard = ("    if isinstance(ehd_b.shape, Facet):\n        raise RuntimeError(")
    unguarded = _yade(wall_export, "sphere-wall", tmp_path, check=False, edit=lambda t: (
        _facet_walls(t).replace(guard, "    if False:\n        raise RuntimeError(")))
    e = np.array([r[s["realises"]["e_realised"]] for r in rows])
    assert np.max(np.array(unguarded) - e) > s["yade"]["realised_max_error"] + MARGIN, unguarded
    # and with block 2 as exported, YADE stops with the snippet's one line
    (tmp_path / "guarded").mkdir()
    with pytest.raises(AssertionError, match="facet walls realise e up to 0.3 too high"):
        _yade(wall_export, "sphere-wall", tmp_path / "guarded", edit=_facet_walls)
