"""Whole trajectories of the two Gondret, Lance & Petit (2002) runs against the measured ones.

Each run (bench_experiments.RUNS[:2]: steel onto glass in silicone oil, St 27 and St 152) settles
from 100 a at the drag law's terminal speed (``ehd scene --trajectory``'s default release), hits
the wall through the scene's near field and rebounds to the top of its first bounce
(solver/trajectory.py). The measured trajectories are the digitized ones in
``../shared/data/gondret2002/`` (README there: source and accuracy). Both are read the same way
(docs/model.md, "Reading e as experiments do"); the St 27 file has no approach points, so its
measured ``e`` rests on the reported impact speed, as the README says. Also the cost: the whole
trajectory's wall time over the near-field solve it contains. Nothing is fitted.

    .venv/bin/python benchmarks/bench_trajectory.py [--data DIR]

writes benchmarks/trajectory.json (with the figures' series), trajectory.md and trajectory.png.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

import harness  # noqa: E402
from bench_experiments import _CLASSIC, _INPUTS, RUNS, load  # noqa: E402

DATA = HERE.parent.parent / "shared" / "data" / "gondret2002"
FILES = ("gondret27_expy.dat", "gondret152_expy.dat")
TOPS_MM = (1.97, 7.47)  # the measured tops of the first bounce (issue 25)
ACCURACY = "standard"
RELEASE_OVER_A = 100.0
VARIANTS = (("scene's own choice", _INPUTS), ("classic film", _CLASSIC))


class _Release:  # the flags run_trajectory reads
    trajectory = None
    release_gap = None
    release_gap_over_a = RELEASE_OVER_A
    release_speed = "settling"
    drag_law = None


def measured(path: Path):
    t, gap = np.loadtxt(path, delimiter=",", unpack=True)
    return t, gap


def read_measured(t, gap, a, impact_speed):
    from solver import trajectory as tj

    u_in, u_out, e, top = tj.observed_restitution(t, gap, tj.READ_WINDOW_OVER_A * a,
                                                  tj.READ_GAP_OVER_A * a)
    source = "fitted"
    if not math.isfinite(u_in):
        u_in, e, source = impact_speed, u_out / impact_speed, "reported impact speed"
    return {"u_in": u_in, "u_out": u_out, "e": e, "top_m": top, "u_in_from": source}


def compute(run, fields):
    import dataclasses

    from pipeline.scenes.run import run_scene
    from pipeline.scenes.trajectory import run_trajectory

    scene = load(run, run.v, fields)
    # a first, untimed run loads what the process loads once (compiled kernels, scipy)
    run_trajectory(scene, _Release, ACCURACY, sensitivity_solves=False)
    start = time.perf_counter()
    result, tr, read, timings = run_trajectory(scene, _Release, ACCURACY,
                                               sensitivity_solves=False)
    total = time.perf_counter() - start
    # the cost to compare with: the scene solved at the same speed without the trajectory (the
    # scene's solves, its automatic switches' included)
    start = time.perf_counter()
    run_scene(dataclasses.replace(scene, v0=tr.v0), accuracy=ACCURACY, sensitivity_solves=False)
    scene_s = time.perf_counter() - start
    c = result.collision
    return tr, {"e_observed": read["e_observed"], "u_in": read["observed_speed_in_m_per_s"],
                "u_out": read["observed_speed_out_m_per_s"],
                "rebound_height_m": read["rebound_height_m"],
                "arrival_speed_m_per_s": read["arrival_speed_m_per_s"],
                "release_speed_m_per_s": read["release_speed_m_per_s"],
                "drag_law": read["drag_law"], "St": result.scene.stokes,
                "e_wet": c.e_wet, "e_far": c.e_far, "status": c.status,
                "energy_residual_over_start": read["trajectory_energy_residual_J"]
                / read["trajectory_energy_J"]["start"],
                "near_field_s": c.wall_s, "scene_s": scene_s, "trajectory_s": total,
                "cost_ratio": total / scene_s}


def flight_from_measured(run, rec: dict) -> dict:
    """The top of the bounce the model's outer motion reaches from the measured departure (the
    speed read from the measured trajectory at the reading gap, with the drag law the computed
    trajectory used): it separates the top's miss into the collision's (the departure speed, as
    ``(e computed / e measured)^2`` of the height) and the flight's (this top against the
    measured one)."""
    from pipeline.scenes.trajectory import _outer
    from solver import trajectory as tj

    law = rec["computed"][VARIANTS[0][0]]["drag_law"]
    outer = _outer(load(run, run.v, VARIANTS[0][1]), law)
    gap0 = tj.READ_GAP_OVER_A * run.diameter / 2
    _, x, _, _, ended = tj.motion(outer, gap0, rec["measured"]["u_out"])
    return {"drag_law": law, "from_gap_m": gap0, "speed_m_per_s": rec["measured"]["u_out"],
            "top_m": float(np.max(x)), "ended": ended}


def measure(data_dir: Path) -> tuple[dict, dict]:
    from solver.far_field import outer_tables
    from solver.model.outer_flow import UNIT_RATIOS

    start = time.perf_counter()  # once per process and geometry (cached), outside the ratios
    outer_tables("wall", UNIT_RATIOS)
    out, curves = {"accuracy": ACCURACY, "release_over_a": RELEASE_OVER_A, "runs": [],
                   "tables_s": time.perf_counter() - start}, {}
    for run, name, top in zip(RUNS[:2], FILES, TOPS_MM):
        a = run.diameter / 2
        t, gap = measured(data_dir / name)
        rec = {"name": run.name, "file": name, "impact_speed_reported": run.v,
               "measured": {**read_measured(t, gap, a, run.v), "top_reported_m": top * 1e-3},
               "computed": {}}
        for label, fields in VARIANTS:
            tr, rec["computed"][label] = compute(run, fields)
            curves[(run.name, label)] = tr
        rec["flight"] = flight_from_measured(run, rec)
        curves[(run.name, "measured")] = (t, gap)
        out["runs"].append(rec)
    return out, curves


def report(data: dict) -> str:
    lines = ["# Whole trajectories against Gondret et al. (2002)", "",
             "Generated by `benchmarks/bench_trajectory.py` (accuracy "
             f"`{data['accuracy']}`); the spheres settle from {data['release_over_a']:g} a at the "
             "drag law's terminal speed. `e` is read the same way from both (docs/model.md, "
             "\"Reading e as experiments do\": parabolas over gaps up to 3 a, speeds compared at "
             "0.1 a); the St 27 file has no approach, its measured `e` rests on the reported "
             "impact speed. Nothing is fitted.", "",
             "| run | trajectory | St (arrival) | arrival speed m/s | e read | top of the first "
             "bounce mm | e_wet (x0) | e_far (0.1 a) | trajectory time / the scene's at that speed |",
             "|---|---|---|---|---|---|---|---|---|"]
    for rec in data["runs"]:
        m = rec["measured"]
        lines.append(f"| {rec['name']} | measured | - | {harness.cell(m['u_in'])} ({m['u_in_from']}) | "
                     f"{harness.cell(m['e'])} | {harness.cell(m['top_m'] * 1e3, '.2f')} (reported "
                     f"{harness.cell(m['top_reported_m'] * 1e3, '.2f')}) | - | - | - |")
        for label, c in rec["computed"].items():
            lines.append(f"| | {label} ({c['drag_law']}) | {harness.cell(c['St'], '.1f')} | "
                         f"{harness.cell(c['arrival_speed_m_per_s'])} | {harness.cell(c['e_observed'])} | "
                         f"{harness.cell(c['rebound_height_m'] * 1e3, '.2f')} | {harness.cell(c['e_wet'])} | "
                         f"{harness.cell(c['e_far'])} | {harness.cell(c['cost_ratio'], '.2f')} |")
    lines += ["", "## Where the top's miss comes from", "",
              "The collision sets the departure speed, the "
              "flight after it the height that speed reaches. The collision's part is the ratio "
              "of the heights the two departure speeds would reach in free flight, `(e computed "
              "/ e measured)^2`; the flight's is the top the model's outer motion reaches from "
              "the measured departure (its speed read at the reading gap 0.1 a) against the "
              "measured top.", "",
              "| run | top measured mm | top computed mm (scene's own choice) | computed / measured "
              "| collision's part (e ratio)^2 | model's flight from the measured departure: top mm "
              "| flight's part (that top / measured) |", "|---|---|---|---|---|---|---|"]
    for rec in data["runs"]:
        m, c, f = rec["measured"], rec["computed"][VARIANTS[0][0]], rec["flight"]
        lines.append(f"| {rec['name']} | {harness.cell(m['top_m'] * 1e3, '.2f')} | "
                     f"{harness.cell(c['rebound_height_m'] * 1e3, '.2f')} | "
                     f"{harness.cell(c['rebound_height_m'] / m['top_m'], '.2f')} | "
                     f"{harness.cell((c['e_observed'] / m['e']) ** 2, '.2f')} | "
                     f"{harness.cell(f['top_m'] * 1e3, '.2f')} | "
                     f"{harness.cell(f['top_m'] / m['top_m'], '.2f')} |")
    lines += ["", f"The resistance tables (built once per process, cached) took "
              f"{data['tables_s']:.2f} s, outside the ratios."]
    return "\n".join(lines) + "\n"


CURVE_POINTS = 600  # a computed trajectory resampled for the figures (its dense near field too)


def aligned_curves(rec: dict, curves: dict) -> dict:
    """The figures' series of one run, time from the first contact [ms] and gap [mm]: every
    computed trajectory from its closest approach, resampled on ``CURVE_POINTS`` uniform times;
    the measured points shifted so that their first rebound point lies on the scene's own
    choice's departure (the files' origin of time is arbitrary)."""
    t, gap = curves[(rec["name"], "measured")]
    first = int(np.nonzero(np.diff(gap) > 0.0)[0][0])  # the first contact
    out, shift = {}, None
    for label, _ in VARIANTS:
        tr = curves[(rec["name"], label)]
        k0 = int(np.argmin(tr.gap))
        if shift is None:
            dep_t, dep_x = tr.t[k0:] - tr.t[k0], tr.gap[k0:]
            top = int(np.argmax(dep_x))
            shift = np.interp(gap[first], dep_x[:top + 1], dep_t[:top + 1]) - t[first]
        ts = np.linspace(tr.t[0], tr.t[-1], CURVE_POINTS)
        gs = np.interp(ts, tr.t, tr.gap)
        ts, gs = np.append(ts, tr.t[k0]), np.append(gs, tr.gap[k0])  # keep the closest approach
        order = np.argsort(ts)
        out[label] = {"t_ms": _rounded((ts[order] - tr.t[k0]) * 1e3),
                      "gap_mm": _rounded(gs[order] * 1e3)}
    out["measured"] = {"t_ms": _rounded((t + shift) * 1e3), "gap_mm": _rounded(gap * 1e3)}
    return out


def _rounded(x) -> list:
    return [float(f"{v:.6g}") for v in x]


def draw_run(ax, rec: dict) -> None:
    """One run's trajectories, computed against measured (``rec["curves"]``), on ``ax``."""
    c = rec["curves"]
    for label, _ in VARIANTS:
        ax.plot(c[label]["t_ms"], c[label]["gap_mm"],
                label=f"{label}: e = {rec['computed'][label]['e_observed']:.2f}")
    t, gap = np.array(c["measured"]["t_ms"]), np.array(c["measured"]["gap_mm"])
    ax.plot(t, gap, "ko", ms=3, label=f"measured: e = {rec['measured']['e']:.2f}")
    ax.set_xlim(t[0] - 15, t[-1] + 5)
    ax.set_ylim(0, 1.3 * max(gap.max(), 1.0))
    ax.set_xlabel("time from the first contact [ms]")
    ax.set_ylabel("gap [mm]")
    ax.set_title(rec["name"])
    ax.legend(loc="upper right", fontsize=7)


def figure(data: dict, out: Path) -> None:
    import matplotlib
    from matplotlib.figure import Figure

    from pipeline.plots.scene_plots import STYLE

    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=(10, 4.2))
        for k, rec in enumerate(data["runs"]):
            draw_run(fig.add_subplot(1, 2, k + 1), rec)
        fig.savefig(out, metadata={"Software": None})


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--data", default=str(DATA), help=f"the measured files' folder (default {DATA})")
    args = p.parse_args(argv)
    load_start = harness.load_now()
    data, curves = measure(Path(args.data))
    for rec in data["runs"]:  # the figures' series (bench_experiments.py draws them too)
        rec["curves"] = aligned_curves(rec, curves)
    data = harness.write_json(HERE / "trajectory.json", data, load_start)
    (HERE / "trajectory.md").write_text(report(data))
    figure(data, HERE / "trajectory.png")
    print(report(data))
    return 0


if __name__ == "__main__":
    sys.exit(main())
