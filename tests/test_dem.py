"""DEM export: fits, the LIGGGHTS replica, exported files, the commands."""

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from pipeline.cli import main
from pipeline.dem import liggghts
from pipeline.dem.conventions import stokes_numbers, store_stokes_numbers
from pipeline.dem.export import CSV_FIELDS, read_csv
from pipeline.dem.fits import fit_exponential, fit_threshold

EXAMPLE = "examples/glass_beads_water.toml"


def test_conventions_for_a_sphere_on_a_wall():
    # 3 mm steel (7800) in glycerol (1260, 1.4 Pa s) at 0.5 m/s on a wall: ours = rho d v / (9 mu)
    rho, d, v, mu = 7800.0, 3e-3, 0.5, 1.4
    m, a = rho * math.pi / 6 * d**3, d / 2
    ours = m * v / (6 * math.pi * mu * a * a)
    row = stokes_numbers(ours, geometry="sphere-wall", rho_p=rho, d=d, v0=v, mu=mu, rho_f=1260.0)
    assert row["St_exp"] == pytest.approx(ours, rel=1e-14)
    assert row["St_L"] == pytest.approx(ours * (1 + 1260 / (2 * 7800)), rel=1e-14)
    # YADE: <rho> (R1 + R2) v / mu with the wall material's density 0: (rho/2) d v / mu
    assert row["St_yade"] == pytest.approx(4.5 * ours, rel=1e-14)


def test_conventions_for_two_equal_spheres():
    # ours uses the reduced mass and radius: twice the experimenters' number of the moving sphere
    rho, d, v, mu = 2500.0, 2e-4, 0.1, 1e-3
    m, a = rho * math.pi / 6 * d**3 / 2, d / 4
    ours = m * v / (6 * math.pi * mu * a * a)
    row = stokes_numbers(ours, geometry="sphere-sphere", rho_p=rho, d=d, v0=v, mu=mu,
                         rho_2=rho, d_2=d)
    assert row["St_exp"] == pytest.approx(ours / 2, rel=1e-14)
    assert row["St_yade"] == pytest.approx(rho * d * v / mu, rel=1e-14)
    assert row["St_yade"] == pytest.approx(4.5 * ours, rel=1e-14)
    # a store row carries both geometries
    store = store_stokes_numbers(ours)
    assert store["St_exp"] == ours and store["St_exp_pair"] == pytest.approx(row["St_exp"])
    assert store["St_yade"] == pytest.approx(row["St_yade"], rel=1e-14)


@pytest.mark.parametrize("law", [fit_exponential, fit_threshold])
def test_fits_reproduce_their_table_within_their_error(law):
    st = np.geomspace(8, 500, 15)
    e = np.where(st > 12, 0.97 * (1 - 12 / st) + 0.01 * np.sin(st), 0.0)  # not of either form
    fit = law(st, e)
    up = e > 0
    # the stated error is the largest residual over the rebounding rows: reproduced exactly
    assert np.max(np.abs(fit(st[up]) - e[up])) == pytest.approx(fit.max_error, rel=1e-12)
    assert fit.st_min == st[up][0] and fit.st_max == st[-1] and fit.st_stick == st[~up][-1]


def test_fits_recover_exact_laws():
    st = np.geomspace(15, 800, 12)
    exp = fit_exponential(st, 0.9 * np.exp(-35 / st))
    thr = fit_threshold(st, 0.95 * (1 - 11 / st))
    # exact data: only the least-squares solvers' tolerances remain (~1e-8)
    assert (exp.e_max, exp.c) == pytest.approx((0.9, 35.0), rel=1e-6)
    assert (thr.e_max, thr.c) == pytest.approx((0.95, 11.0), rel=1e-10)


@pytest.mark.parametrize("log_e", [-0.05, -0.7, -2.5])
def test_replica_with_fixed_stokes_gives_its_target_exactly(log_e):
    # damping from a fixed St: linear spring-dashpot, e = exp(-zeta pi/sqrt(1 - zeta^2)) = exp(L)
    e_max, st_crit, st_fixed = 0.9, -(log_e - math.log(0.9)) * 20.0, 20.0
    realised = liggghts.replica_restitution(7.0, e_max, st_crit, fixed_stokes=st_fixed)
    assert liggghts.closed_form_restitution(log_e) == pytest.approx(math.exp(log_e), rel=1e-14)
    # integration to rtol 1e-10 over half an oscillation: agreement to ~1e-9
    assert realised == pytest.approx(math.exp(log_e), rel=1e-8)


def test_replica_with_instantaneous_stokes_differs_and_calibration_fixes_it():
    st = np.array([20.0, 40.0, 80.0, 160.0, 320.0])
    target = 0.95 * np.exp(-15.0 / st)
    plain = np.array([liggghts.replica_restitution(s, 0.95, 15.0) for s in st])
    assert np.max(np.abs(plain - target)) > 0.05  # the law is not realised as written
    e_max, c, err, realised = liggghts.calibrate(st, target, 0.95, 15.0)
    assert err < np.max(np.abs(plain - target)) and 0 < e_max <= 1 and c > 0
    assert np.max(np.abs(realised - target)) == pytest.approx(err)


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    out = tmp_path_factory.mktemp("dem")
    # the example cavitates (water at 1 atm): St_c ~ 6 instead of the classic film's ~ 12, so
    # the path starts at 0.2 v0 (St ~ 2) to include sticking
    assert main(["restitution", EXAMPLE, "--accuracy", "fast", "--from", "0.2", "--to", "6",
                 "--n", "7", "--out", str(out)]) == 0
    return out


def test_exported_files_parse(exported):
    rows = read_csv(exported / "restitution.csv")
    assert len(rows) == 7 and tuple(rows[0]) == CSV_FIELDS
    assert rows[0]["sticks"] and rows[0]["e_wet"] == 0.0 and not rows[-1]["sticks"]
    # glass at 1 nm rms against the sub-nm films of the rebounding collisions: the scenes model
    # the asperity contact (docs/scenes.md, "Surface roughness"), so no row warns of roughness
    assert not any("roughness" in r["warning_checks"].split() for r in rows)
    # every validity warning is carried, not only the roughness one: fluid inertia at the top
    # speeds (Re x0/a > 0.1 from about 2 v0 for 200 um beads in water), one message per check
    assert "Re_x0_over_a" in rows[-1]["warning_checks"].split()
    assert all(len(r["warning"].split("; ")) >= len(r["warning_checks"].split()) for r in rows)
    assert all(r["geometry"] == "sphere-sphere" for r in rows)
    doc = json.loads((exported / "restitution.json").read_text())
    (group,) = doc["groups"].values()
    assert set(group["fits"]) == {"St", "St_exp", "St_L", "St_yade"}  # no pair columns: a scene
    for conv in ("St", "St_exp", "St_L", "St_yade"):
        for law in ("exponential", "threshold"):
            fit = group["fits"][conv][law]
            assert fit["convention"] == conv and fit["max_error"] < 0.1 and fit["e_max"] <= 1
    # CSV round trip: the fit's stated error is reproduced from the CSV's own numbers
    fit = group["fits"]["St"]["threshold"]
    st = np.array([r["St"] for r in rows if r["e_wet"] > 0])
    e = np.array([r["e_wet"] for r in rows if r["e_wet"] > 0])
    pred = fit["e_max"] * (1 - fit["c"] / st)
    assert np.max(np.abs(pred - e)) == pytest.approx(fit["max_error"], rel=1e-9)

    lig = next(exported.glob("liggghts_*.in")).read_text()
    assert "pair_style gran model hooke" in lig and "viscous on" in lig
    for key in ("FluidViscosity", "CriticalStokes", "MaximumRestitution"):
        m = re.search(rf"fix \S+ all property/global {key} peratomtypepair (\d+) (.*)", lig)
        n = int(m.group(1))
        assert len(m.group(2).split()) == n * n  # an n x n matrix
    for key in ("youngsModulus", "poissonsRatio"):
        m = re.search(rf"property/global {key} peratomtype (.*)", lig)
        assert len(m.group(1).split()) == n
    # two spheres: no wall line, no OpenFOAM (a patch interaction: walls only)
    assert not list(exported.glob("liggghts_*_wall.in")) and not list(exported.glob("openfoam_*"))
    assert "openfoam" not in group
    yade = next(exported.glob("yade_*.py")).read_text()
    compile(yade, "yade", "exec")  # valid Python
    for key in ("ViscElMat(", "en=", "lubrication=True", "viscoDyn=", "roughnessScale="):
        assert key in yade
    assert "BLOCK 2" not in yade  # the wall-mass block: walls only


def test_export_dem_from_a_scene_file(tmp_path, capsys):
    assert main(["export-dem", EXAMPLE, "--accuracy", "fast", "--n", "5",
                 "--out", str(tmp_path)]) == 0
    rows = read_csv(tmp_path / "restitution.csv")
    assert len(rows) == 5 and rows[0]["St"] < rows[-1]["St"]
    assert main(["export-dem", str(tmp_path / "nothing.zarr")]) == 2


def test_export_dem_from_a_sweep_store(tmp_path, capsys):
    # a real (fast) sweep: e_wet goes into the store from the registry and out to the CSV
    from pipeline import open_results
    from pipeline.sweeps.config import parse_sweep
    from pipeline.sweeps.run import run_sweep
    from solver import collide

    text = ('name = "dem"\nstore = "x.zarr"\n[grid]\nSt = [6.0, 10.0, 15.0, 30.0, 60.0]\n'
            'eps = [0.01]\n[numerics]\naccuracy = "fast"\n')
    sweep = parse_sweep(text).with_store(tmp_path / "s.zarr")
    run_sweep(sweep, runner="serial", progress=None)
    ds = open_results(sweep.store)
    assert float(ds.e_wet.sel(St=30.0, eps=0.01)) == collide(30.0, 0.01, accuracy="fast").e_wet
    assert main(["export-dem", str(sweep.store), "--out", str(tmp_path / "out")]) == 0
    rows = read_csv(tmp_path / "out" / "restitution.csv")
    assert [r["St"] for r in rows] == [6.0, 10.0, 15.0, 30.0, 60.0]
    assert rows[0]["sticks"] and rows[0]["St_exp"] == 6.0 and rows[0]["St_yade"] == 27.0
    assert rows[0]["St_exp_pair"] == 3.0 and rows[0]["geometry"] == "either"
    doc = json.loads((tmp_path / "out" / "restitution.json").read_text())
    assert set(doc["groups"]) == {"eps=0.01"}
    group = doc["groups"]["eps=0.01"]
    assert group["liggghts"]["MaximumRestitution"] <= 1.0
    # both geometries: fits on the pair conventions too
    assert {"St_exp_pair", "St_L_pair"} <= set(group["fits"])
    out = tmp_path / "out"
    lig = (out / "liggghts_eps_0.01.in").read_text()
    for line in ("hard_particles yes", "pair_style gran model hooke tangential history viscous on",
                 "coefficientFriction", "characteristicVelocity", "variable ehd_dt_max"):
        assert line in lig
    # a store has no materials: every physical value is an example marked REPLACE
    for var in ("viscosity", "youngs", "poisson", "vchar", "density", "radius", "friction"):
        assert re.search(rf"^variable ehd_{var} equal \S+ +# REPLACE", lig, re.M), var
    wall = (out / "liggghts_eps_0.01_wall.in").read_text()
    assert re.search(r"wall/gran model hooke tangential history primitive type 1 zplane \S+ "
                     r"viscous on$", wall, re.M)  # model keywords after the wall's arguments
    yade = (out / "yade_eps_0.01.py").read_text()
    compile(yade, "yade", "exec")
    assert "ehd_wall_mat" in yade and "BLOCK 2" in yade and yade.count("# REPLACE") >= 5
    foam = (out / "openfoam_eps_0.01.txt").read_text()
    # the keywords the library reads (src/patchInteractionDataHW.C), its libs line, the
    # dictionary named; rhoF 0 as the fit's St_L assumed (--density-ratio 0)
    for key in ('libs ("libLocalInteractionModelHW.so");', "kinematicCloudProperties",
                "patchInteractionModel localInteractionHW;", "localInteractionHWCoeffs",
                "type       rebound;", "coeffStc", "muP"):
        assert key in foam
    assert re.search(r"^ +rhoF +0;", foam, re.M) and re.search(r"^ +e +[0-9.]+;", foam, re.M)
    code = re.sub(r"//.*", "", foam)  # balanced outside the comments
    assert code.count("{") == code.count("}") == 2 and code.count("(") == code.count(")") == 2
    of = group["openfoam"]
    assert of["realised_max_error"] >= max(b["max_error"] for b in of["realised_error_by_St"]) - 1e-15


def test_liggghts_snippet_raises_a_slow_characteristic_velocity():
    lig = {"realised_max_error": 0.02, "CriticalStokes": 10.0, "MaximumRestitution": 0.9}
    text = liggghts.snippet(lig, types=["glass"], placeholders=False, values={
        "youngs": [7e10], "poisson": [0.22], "viscosity": 1e-3, "v_char": 0.004, "dt_max": 1e-9})
    # LIGGGHTS refuses characteristicVelocity < 1e-2 in SI units; it sets kn only
    assert re.search(r"characteristicVelocity scalar 0.01 ", text)
    assert "REPLACE" in text and text.count("REPLACE") == 1  # friction only: the scene's values


def test_liggghts_contact_time_is_the_hooke_half_period():
    # kn from LIGGGHTS' formula; pi sqrt(m/k) by hand for 200 um glass on a glass wall
    m, r, y = 2500 * 4 / 3 * math.pi * 1e-4**3, 1e-4, 7e10
    yeff = liggghts.effective_modulus(y, 0.25, y, 0.25)
    assert yeff == pytest.approx(y / (2 * (1 - 0.25**2)), rel=1e-14)
    kn = 16 / 15 * math.sqrt(r) * yeff * (15 * m * 0.1**2 / (16 * math.sqrt(r) * yeff)) ** 0.2
    assert liggghts.contact_time(m, r, yeff, 0.1) == pytest.approx(math.pi * math.sqrt(m / kn),
                                                                   rel=1e-14)


# ---- bad input: one line, the documented exit code, no partial files ------------------------

def _tiny_store(path, st):
    from pipeline.sweeps.config import parse_sweep
    from pipeline.sweeps.run import run_sweep

    text = (f'name = "dem-bad"\nstore = "x.zarr"\n[grid]\nSt = {list(st)}\neps = [0.01]\n'
            '[numerics]\naccuracy = "fast"\n')
    sweep = parse_sweep(text).with_store(path)
    run_sweep(sweep, runner="serial", progress=None)
    return sweep.store


def _one_error_line(capsys, code_expected, code):
    err = capsys.readouterr().err.strip().splitlines()
    assert code == code_expected and len(err) == 1 and err[0].startswith("ehd export-dem: error:")
    return err[0]


def test_export_dem_refuses_a_store_without_finished_scenes(tmp_path, capsys):
    import zarr

    store = _tiny_store(tmp_path / "s.zarr", [20.0, 40.0, 80.0])
    zarr.open_group(str(store), mode="r+")["status"][:] = 0  # as if never run
    capsys.readouterr()
    line = _one_error_line(capsys, 2, main(["export-dem", str(store), "--out", str(tmp_path / "o")]))
    assert "no finished" in line
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())


def test_export_dem_refuses_a_store_where_nothing_rebounds(tmp_path, capsys):
    # eps 1e-2 sticks below St ~ 8: nothing to fit
    store = _tiny_store(tmp_path / "s.zarr", [0.5, 1.0, 2.0])
    capsys.readouterr()
    out = tmp_path / "o"
    line = _one_error_line(capsys, 2, main(["export-dem", str(store), "--out", str(out)]))
    assert "no collision rebounds" in line
    assert not out.exists() or not any(out.iterdir())


def test_export_dem_refuses_an_unwritable_out_before_any_work(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    line = _one_error_line(capsys, 2, main(["export-dem", EXAMPLE, "--out",
                                            str(tmp_path / "file" / "sub")]))
    assert "--out" in line


def test_interrupted_export_leaves_no_file(tmp_path, capsys, monkeypatch):
    # Ctrl-C during the calibration: exit 130, nothing written (files are written only after
    # every group is computed, each under a temporary name renamed into place)
    store = _tiny_store(tmp_path / "s.zarr", [10.0, 15.0, 30.0, 60.0])
    out = tmp_path / "o"

    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(liggghts, "calibrate", interrupt)
    assert main(["export-dem", str(store), "--out", str(out)]) == 130
    assert not out.exists() or not list(out.iterdir())


def test_write_files_leaves_the_old_export_when_a_write_fails(tmp_path, monkeypatch):
    import builtins
    import errno

    import pipeline.writes
    from pipeline.dem import export
    from pipeline.errors import WriteError

    export.write_files({"a.txt": "old a", "b.txt": "old b"}, tmp_path)

    def fail_on_b(path, *a, **k):
        if ".b.txt" in Path(path).name:
            raise OSError(errno.ENOSPC, "No space left on device")
        return builtins.open(path, *a, **k)

    monkeypatch.setattr(pipeline.writes, "open", fail_on_b, raising=False)
    with pytest.raises(WriteError, match="b.txt"):  # the file being written, in one line
        export.write_files({"a.txt": "new a", "b.txt": "new b"}, tmp_path)
    monkeypatch.undo()
    # nothing renamed (a.txt is still the old one) and no temporary file left behind
    assert (tmp_path / "a.txt").read_text() == "old a"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.txt"]


def test_fit_range_fits_only_there_and_reports_every_row(tmp_path):
    store = _tiny_store(tmp_path / "s.zarr", [6.0, 10.0, 15.0, 30.0, 60.0, 120.0])
    out_all, out_near = tmp_path / "all", tmp_path / "near"
    assert main(["export-dem", str(store), "--out", str(out_all)]) == 0
    assert main(["export-dem", str(store), "--out", str(out_near), "--fit-range", "10", "30"]) == 0
    g_all = json.loads((out_all / "restitution.json").read_text())["groups"]["eps=0.01"]
    g_near = json.loads((out_near / "restitution.json").read_text())["groups"]["eps=0.01"]
    assert g_near["fit_range"]["n"] == 3 and g_near["fits"]["St"]["threshold"]["n"] <= 3
    rows = [r for r in read_csv(out_all / "restitution.csv") if 10 <= r["St"] <= 30]
    st, e = np.array([r["St"] for r in rows]), np.array([r["e_wet"] for r in rows])

    def lig_err(g):
        lig = g["liggghts"]
        return np.max(np.abs(liggghts.replica_many(st, lig["MaximumRestitution"],
                                                   lig["CriticalStokes"]) - e))

    # calibrated where the collisions are: better there than the calibration over every row
    assert lig_err(g_near) == pytest.approx(g_near["liggghts"]["realised_max_error_fit_range"])
    assert lig_err(g_near) < lig_err(g_all)
    for code in ("liggghts", "openfoam", "yade"):  # errors still reported on every row
        assert sum(b["n"] for b in g_near[code]["realised_error_by_St"]) == 6
    assert main(["export-dem", str(store), "--out", str(out_near), "--fit-range", "30", "10"]) == 2


def test_store_with_a_further_axis_groups_by_it(tmp_path):
    # a cavitation store (St, eps, Pi): one group per (eps, Pi), each with its own settings
    from pipeline.sweeps.config import parse_sweep
    from pipeline.sweeps.run import run_sweep

    text = ('name = "dem-pi"\nstore = "x.zarr"\n[grid]\nSt = [10.0, 15.0, 30.0, 60.0]\n'
            'eps = [0.01]\nPi = [0.01, 1.0]\n[physics]\ncavitation = "jfo"\n'
            '[numerics]\naccuracy = "fast"\n')
    sweep = parse_sweep(text).with_store(tmp_path / "s.zarr")
    run_sweep(sweep, runner="serial", progress=None)
    assert main(["export-dem", str(sweep.store), "--out", str(tmp_path / "o")]) == 0
    rows = read_csv(tmp_path / "o" / "restitution.csv")
    assert {r["group"] for r in rows} == {"eps=0.01 Pi=0.01", "eps=0.01 Pi=1"}
    assert len(rows) == 8
    doc = json.loads((tmp_path / "o" / "restitution.json").read_text())
    assert set(doc["groups"]) == {"eps=0.01 Pi=0.01", "eps=0.01 Pi=1"}
