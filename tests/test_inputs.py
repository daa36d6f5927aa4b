"""Bad input gets a clear message naming the parameter and its valid range; the CLI contract."""

import json
import math
import re
import subprocess
import sys

import numpy as np
import pytest

from solver import JSON_KEYS, collide
from solver.integration.radii import MAX_NODES, reference_radii
from solver.settings import resolve


@pytest.mark.parametrize("stokes, eps, needle", [
    (0.0, 0.01, "St (Stokes number) = 0.0 is outside its valid range (0, 10000]"),
    (-1.0, 0.01, "St (Stokes number)"),
    (math.nan, 0.01, "St (Stokes number) must be finite"),
    (math.inf, 0.01, "St (Stokes number) must be finite"),
    ("five", 0.01, "St (Stokes number) must be a number"),
    (5.0, 0.0, "eps (elasticity parameter) = 0.0 is outside its valid range (0, 0.1]"),
    (5.0, 0.5, "eps (elasticity parameter) = 0.5 is outside its valid range (0, 0.1]"),
    (5.0, -1e-3, "eps (elasticity parameter)"),
])
def test_bad_scene_parameters(stokes, eps, needle):
    with pytest.raises(ValueError, match=re.escape(needle)):
        collide(stokes, eps)


def test_bad_numerics():
    with pytest.raises(ValueError, match=r"accuracy must be one of \['fast', 'fine', 'standard'\]"):
        collide(5, 0.01, accuracy="superb")
    with pytest.raises(ValueError, match="unknown numerical setting 'grid'"):
        collide(5, 0.01, grid=3)
    with pytest.raises(ValueError, match=r"rtol = 0.5 is outside its valid range"):
        collide(5, 0.01, rtol=0.5)
    with pytest.raises(ValueError, match=r"release \(0.1\) must be smaller than switch"):
        collide(5, 0.01, release=0.1)
    with pytest.raises(ValueError, match="n_inner must be a whole number"):
        collide(5, 0.01, n_inner=32.5)
    for order, needle in ((0, r"max_order = 0 is outside its valid range \(0, 5\]"),
                          (6, r"max_order = 6 is outside its valid range"),
                          (2.5, "max_order must be a whole number")):
        with pytest.raises(ValueError, match=needle):
            collide(5, 0.01, max_order=order)
    for factor, needle in ((0.0, r"high_order_rtol_factor = 0.0 is outside its valid range"),
                           (1e3, r"high_order_rtol_factor = 1000.0 is outside its valid range"),
                           ("four", "high_order_rtol_factor must be a number")):
        with pytest.raises(ValueError, match=needle):
            collide(5, 0.01, high_order_rtol_factor=factor)


def test_numerics_take_numbers_and_flags_only_true_or_false():
    """``max_order = true`` (a bool is 1 to ``float``) ran BDF1 unannounced and moved v_r, and
    ``rtol = "1e-4"`` (a string) passed; ``save_profiles = "no"`` read as True (a hostile
    review). numpy's numbers and bools are what they say."""
    for kw, needle in ((dict(max_order=True), "max_order must be a number, got True"),
                       (dict(rtol="1e-4"), "rtol must be a number, got '1e-4'"),
                       (dict(save_profiles="no"), "save_profiles must be true or false"),
                       (dict(extrapolate=1), "extrapolate must be true or false"),
                       (dict(accuracy=["fast"]), "accuracy must be one of")):
        with pytest.raises(ValueError, match=re.escape(needle)):
            resolve(**{"accuracy": "fast", **kw})
    assert resolve("fast", rtol=np.float64(1e-4), n_inner=np.int64(40)).n_inner == 40
    assert resolve("fast", extrapolate=np.True_).extrapolate is True


def test_a_grid_too_large_for_memory_is_refused_and_an_axis_zone_to_1_ends_there():
    """``stretch = 1`` with ``outer_extent = 1e4`` asked for a 6.9 TiB elastic matrix (a raw
    MemoryError); ``axis_extent = 1`` (in its range) stepped past the inner region's end, whose
    last cell came out negative, and the grid's outer loop never ended (a hostile review)."""
    with pytest.raises(ValueError, match=f"more than {MAX_NODES} nodes"):
        resolve("fast", stretch=1.0, outer_extent=1e4)
    for ratio in (0.1, 0.011, 0.5):
        r = reference_radii(32, ratio, 1.0, 1.25, 30.0, 0.3)
        assert np.all(np.diff(r) > 0) and r[-1] >= 30.0 and 1.0 in r
        inner = np.diff(r[r <= 1.0])
        # the refined zone's cells grow towards the uniform size 1/32 and it ends at 1 within
        # half a cell: its last cell is between half and one and a half of the one before it
        assert inner.max() <= 1.5 / 32 and 0.5 * inner[-2] <= inner[-1] <= 1.5 * inner[-2]
    preset = resolve("fast")  # a preset's grid, as it always was: the zone ends before 1
    r = reference_radii(preset.n_inner, preset.axis_ratio, preset.axis_extent, preset.stretch,
                        preset.outer_extent, preset.max_rel)
    uniform = np.diff(r[(r >= 0.5) & (r <= 1.0)])  # the linspace to 1 after the zone
    assert np.all(np.diff(r) > 0) and np.allclose(uniform, uniform[0], rtol=1e-9)
    assert abs(uniform[0] * 32 - 1.0) < 0.05  # the zone's end rounded to whole cells of 1/32


def test_odd_python_values_get_the_groups_own_message():
    """An int beyond any float raised OverflowError, an array where a choice goes numpy's
    "truth value of an array is ambiguous" (a hostile review): each is the group's ValueError."""
    from solver import Physics

    with pytest.raises(ValueError, match=re.escape("St (Stokes number) is a number beyond")):
        Physics(St=10**400, eps=0.01)
    with pytest.raises(ValueError, match="cavitation .* must be one of"):
        Physics(St=10.0, eps=0.01, Pi=1.0, cavitation=np.array(["jfo", "off"]))
    assert Physics(St=10.0, eps=0.01, Pi=1.0, cavitation=np.str_("jfo")).cavitation == "jfo"


def _ehd(*args):
    return subprocess.run([sys.executable, "-m", "pipeline.cli", *args], capture_output=True,
                          text=True, timeout=300)


def test_cli_run_json_contract():
    out = _ehd("run", "--St", "5", "--eps", "0.01", "--accuracy", "fast", "--switch", "0.05",
               "--json")
    assert out.returncode == 0, out.stderr
    lines = out.stdout.strip().splitlines()
    assert len(lines) == 1  # exactly one JSON object
    d = json.loads(lines[0])
    for key in ("St", "eps", "model", "status", "v_r", "h_m_x1", "h_m_x0", "h_m_approach_x1",
                "x_e_x1", "x_e_x0", "tau_max_deformation", "tau_v_zero", "tau_max_rebound",
                "peak_force", "dimple", "escaped", "energy_error", "wall_s"):
        assert key in d
    assert set(JSON_KEYS) == set(d)
    assert d["status"] == "ok" and d["model"] == "ehd" and d["St"] == 5.0


@pytest.mark.parametrize("args, needle", [
    (["--St", "-2", "--eps", "0.01"], "St (Stokes number) = -2.0 is outside its valid range"),
    (["--St", "nan", "--eps", "0.01"], "St (Stokes number) must be finite"),
    (["--St", "5", "--eps", "0.3"], "eps (elasticity parameter) = 0.3 is outside"),
    (["--St", "5", "--eps", "0.01", "--accuracy", "best"], "accuracy must be one of"),
    (["--St", "5", "--eps", "0.01", "--save", "x.txt"], "unknown file type"),
])
def test_cli_bad_input_exits_2_without_traceback(args, needle):
    out = _ehd("run", *args)
    assert out.returncode == 2
    assert needle in out.stderr and "Traceback" not in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1


def test_cli_failed_scene_exits_1_with_reason():
    out = _ehd("run", "--St", "30", "--eps", "0.01", "--max-steps", "20", "--json")
    assert out.returncode == 1
    d = json.loads(out.stdout)
    assert d["status"] == "max_steps" and "step budget" in d["message"]


# ---- ehd run: flags from the physics declaration, report rows from the registry -------------
def test_cli_run_flags_come_from_the_physics_groups(capsys):
    from pipeline.cli import main
    from solver.physics import GROUPS

    with pytest.raises(SystemExit):
        main(["run", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())  # argparse wraps lines
    for group in GROUPS:
        assert group.option in help_text and group.long_name in help_text


def test_cli_run_report_has_a_row_for_each_labelled_observable(capsys):
    from pipeline.cli import main
    from solver.observables import OBSERVABLES
    from solver.physics import Physics

    assert main(["run", "--St", "5", "--eps", "0.01", "--accuracy", "fast"]) == 0
    lines = capsys.readouterr().out.splitlines()
    labels = [o.label for o in OBSERVABLES if o.label]
    expected = [*Physics.names(), "model", "status", *labels]
    # one row per label, in this order, label then two spaces and the value
    rows = [line for line in lines if any(line.startswith(k + "  ") for k in expected)]
    assert len(rows) == len(expected)
    for row, label in zip(rows, expected):
        assert row.startswith(label + "  ") and row[len(label):].strip()


@pytest.mark.parametrize("make, flag, needle", [
    (lambda tmp: "/nonexistent/d/x.nc", "--save", "does not exist"),
    (lambda tmp: str(tmp / "missing" / "x.zarr"), "--save", "does not exist"),
    (lambda tmp: (tmp / "f.zarr").write_text("") or str(tmp / "f.zarr"), "--save",
     "not a directory"),
    (lambda tmp: (tmp / "d.nc").mkdir() or str(tmp / "d.nc"), "--save", "is a directory"),
    (lambda tmp: (tmp / "figs").write_text("") or str(tmp / "figs"), "--plot",
     "not a directory"),
])
def test_cli_run_unwritable_output_exits_2_before_solving(tmp_path, capsys, monkeypatch, make,
                                                          flag, needle):
    import solver
    from pipeline.cli import main

    monkeypatch.setattr(solver, "collide", lambda *a, **k: pytest.fail("solved"))
    assert main(["run", "--St", "5", "--eps", "0.01", flag, make(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and "Traceback" not in err and len(err.splitlines()) == 1


def test_cli_run_save_into_missing_directory_is_refused_fast():
    out = _ehd("run", "--St", "5", "--eps", "0.01", "--save", "/nonexistent/d/x.nc")
    assert out.returncode == 2 and out.stdout == ""
    assert "/nonexistent/d" in out.stderr and len(out.stderr.strip().splitlines()) == 1


def test_cli_output_into_a_closed_pipe_has_no_traceback():
    out = subprocess.run(f"'{sys.executable}' -m pipeline.cli run --St 5 --eps 0.01 "
                         "--accuracy fast | head -1", shell=True, capture_output=True, text=True,
                         timeout=300)
    assert out.stdout.startswith("St")
    assert "Traceback" not in out.stderr and "BrokenPipeError" not in out.stderr
    # a reader that never reads: the write meets a closed pipe (no solve needed for the output)
    out = subprocess.run(["bash", "-o", "pipefail", "-c",
                          f"'{sys.executable}' -m pipeline.cli scene --list-materials | true"],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode in (0, 141) and out.stderr == ""
