"""Scene figures and the paper figures 2-11: they render (Agg), reproducibly, from a collision."""

import math

import numpy as np
import pytest

from pipeline.cli import main
from pipeline.plots.paper_figures import (FIGURES, PAPER_EPS, PAPER_STOKES, deformation_integral,
                                    kernel_of_ratio, paper_figures)
from pipeline.plots.scene_plots import dimple_rows, plot_scene, profile_rows
from solver import collide


@pytest.fixture(scope="module")
def fast_paper():
    # accuracy "fast": these tests are about the figures, not about the numbers
    return {st: collide(st, PAPER_EPS, accuracy="fast") for st in PAPER_STOKES}


def test_deformation_integral_at_zero_and_far_field():
    # I(0) = pi^2/(4 sqrt 2) exactly (docs/model.md, "Small deformation"); quad is asked for 1e-11 relative
    assert deformation_integral(0.0) == pytest.approx(math.pi**2 / (4 * math.sqrt(2)), rel=1e-9)
    # I(xi) ~ pi/(2 xi): the first correction is O(ln(xi)/xi^2) (the kernel's next term, pi s/2
    # times (1 + O(s^2)), integrated against 1/(1+eta^2/2)^2), i.e. ~5e-4 at xi = 100
    r100 = 100 * deformation_integral(100.0) / (math.pi / 2)
    r1000 = 1000 * deformation_integral(1000.0) / (math.pi / 2)
    assert abs(r100 - 1) < 1e-3
    assert abs(r1000 - 1) < abs(r100 - 1) / 30  # falls faster than 1/xi
    # I is largest at 0 and decreasing (docs/model.md, "Small deformation")
    xi = np.array([0.0, 0.3, 1.0, 3.0, 10.0])
    values = [deformation_integral(x) for x in xi]
    assert np.all(np.diff(values) < 0)


def test_kernel_limits():
    # phi -> pi s/2 for s = y/r -> 0 and -> pi/2 for s -> inf; relative corrections O(s^2), O(1/s)
    assert kernel_of_ratio(1e-4) == pytest.approx(math.pi / 2 * 1e-4, rel=1e-6)
    assert kernel_of_ratio(1e6) == pytest.approx(math.pi / 2, rel=1e-5)


def test_plot_scene_writes_reproducible_files(tmp_path, fast_paper):
    c = fast_paper[5.0]
    first = plot_scene(c, tmp_path / "a", title="St 5")
    second = plot_scene(c, tmp_path / "b", title="St 5")
    stems = {p.stem for p in first}
    assert stems == {"gap", "deformation", "pressure", "motion", "energy"} | (
        {"dimple"} if c.dimple else set())
    # the names a command checks in --plot before the solve (pipeline.plots) are these
    from pipeline.plots import SCENE_FIGURES, figure_files

    assert {p.name for p in first} <= set(figure_files(SCENE_FIGURES))
    for p, q in zip(first, second):
        assert p.stat().st_size > 10_000
        assert p.read_bytes() == q.read_bytes(), p.name  # no timestamps / versions in the files


def test_plot_scene_rigid_has_no_profile_figures(tmp_path):
    c = collide(1.0, 1e-5, accuracy="fast")
    assert c.model == "rigid"
    assert {p.stem for p in plot_scene(c, tmp_path)} == {"motion", "energy"}


def test_profile_and_dimple_rows(fast_paper):
    c = fast_paper[5.0]
    rows = profile_rows(c, 8)
    assert 4 <= rows.size <= 8 and np.all(np.diff(rows) > 0)
    # the v = 0 instant is one of the shown times (to within one saved step)
    assert np.min(np.abs(c.profile_tau[rows] - c.tau_v_zero)) <= np.max(np.diff(c.profile_tau))
    c10 = fast_paper[10.0]
    if c10.dimple:
        d = dimple_rows(c10)
        h = c10.gap[d]
        assert np.all(h[:, 0] > h.min(axis=1))  # each shown profile has its minimum off the axis


def test_paper_figures_writes_figures_2_to_11(tmp_path, fast_paper):
    paths = paper_figures(tmp_path, collisions=fast_paper)
    assert [p.stem for p in paths if p.suffix == ".png"] == list(FIGURES)
    from pipeline.plots import figure_files  # what ehd paper-figures checks in --out first

    assert sorted(p.name for p in paths) == sorted(figure_files(FIGURES))
    assert all(p.exists() and p.stat().st_size > 5_000 for p in paths)


def test_cli_scene_plot_and_paper_figures_bad_accuracy(tmp_path, capsys):
    scene = tmp_path / "s.toml"
    scene.write_text('v0 = "10 cm/s"\n[body1]\nmaterial = "glass"\nradius = "100 um"\n'
                     '[body2]\nmaterial = "glass"\nwall = true\n[fluid]\nname = "water"\n')
    assert main(["scene", str(scene), "--accuracy", "fast", "--plot", str(tmp_path / "f")]) == 0
    assert (tmp_path / "f" / "motion.png").exists()
    assert main(["paper-figures", "--out", str(tmp_path / "p"), "--accuracy", "sloppy"]) == 2
    assert "accuracy" in capsys.readouterr().err


def test_cli_run_plot(tmp_path, capsys):
    assert main(["run", "--St", "5", "--eps", "0.01", "--accuracy", "fast",
                 "--plot", str(tmp_path)]) == 0
    assert "figures:" in capsys.readouterr().out
    assert {p.stem for p in tmp_path.glob("*.png")} >= {"gap", "deformation", "pressure",
                                                        "motion", "energy"}


def test_restitution_curve_rises_from_zero_at_the_threshold_not_below_it():
    """A straight line from the last sticking scene to the first rebounding one showed e > 0
    below the bisected St_c (e_far about 0.07 at St 10, St_c 11.04: a hostile scan): the
    rebounding line starts at (St_c, 0), the line along 0 ends there. Log axes label their
    minor ticks at 2 and 5 only over more than half a decade (3 and 4 ran into each other)."""
    import types

    from matplotlib.figure import Figure

    from pipeline.plots.restitution_plot import _curve, _minor_labels

    def result(e):
        return types.SimpleNamespace(collision=types.SimpleNamespace(e_far=e), answer={})

    ok = [result(0.0), result(0.0), result(0.6), result(0.8)]
    st = np.array([3.0, 10.0, 20.0, 60.0])
    ax = Figure().subplots()
    t = types.SimpleNamespace(key="e_far", St_c=11.04)
    _curve(ax, ok, st, "e_far", [t])
    zero, rise = ax.lines[0].get_xydata(), ax.lines[1].get_xydata()
    assert zero.tolist() == [[3.0, 0.0], [10.0, 0.0], [11.04, 0.0]]
    assert rise.tolist() == [[11.04, 0.0], [20.0, 0.6], [60.0, 0.8]]
    ax.set_xscale("log")
    ax.set_xlim(2.0, 80.0)
    label = _minor_labels(ax.xaxis)
    assert [label(x) for x in (3.0, 4.0, 5.0, 20.0)] == [
        "", "", r"$5\times10^{0}$", r"$2\times10^{1}$"]
    ax.set_xlim(15.0, 22.0)  # a short axis: every minor tick
    assert label(17.0) == r"$1.7\times10^{1}$"
