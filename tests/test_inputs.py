"""Bad input gets a clear message naming the parameter and its valid range; the CLI contract."""

import json
import math
import re
import subprocess
import sys

import pytest

from solver import JSON_KEYS, collide


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
