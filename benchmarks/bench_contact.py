"""What a rough collision costs against the smooth one at the same preset (issue 17's target: at
most 2x), alternated scene by scene in one process so both share the machine's load.

Scenes: the standard preset, St 10-100 x eps 1e-4 and 1e-5, roughness 0.5 and 1 x1 (a polished
steel ball on glass is about 0.6 x1, docs/model.md "Surface roughness"), asperity stiffness 2
and 20, e_dry 0.97. Each scene is solved ``REPEATS`` times on each side, alternately, after one
warm-up solve of each (compilation); the table gives the CPU-time medians, their ratio and the
counters of both.

``python benchmarks/bench_contact.py [--quick]`` (about two minutes; ``make bench``) writes
``benchmarks/contact.md`` (``--quick``: two scenes, written to /tmp).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from solver import SOLVER_VERSION, Physics, collide  # noqa: E402

HERE = Path(__file__).parent
REPEATS = 3
SCENES = [(st, eps, sigma, k) for st in (10.0, 30.0, 100.0) for eps in (1e-4, 1e-5)
          for sigma, k in ((0.5, 20.0), (1.0, 2.0))]


def _cpu(physics):
    start = time.process_time()
    result = collide(physics)
    return time.process_time() - start, result


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    scenes = SCENES[:2] if args.quick else SCENES
    out = Path("/tmp/contact.md") if args.quick else HERE / "contact.md"
    rows, ratios = [], []
    for st, eps, sigma, k in scenes:
        smooth = Physics(St=st, eps=eps)
        rough = Physics(St=st, eps=eps, roughness=sigma, asperity_stiffness=k, e_dry=0.97)
        _cpu(smooth), _cpu(rough)  # compile, fill caches
        t_s, t_r = [], []
        for _ in range(REPEATS):
            t, res_s = _cpu(smooth)
            t_s.append(t)
            t, res_r = _cpu(rough)
            t_r.append(t)
        ratio = statistics.median(t_r) / statistics.median(t_s)
        ratios.append(ratio)
        touched = res_r.series["F_contact"].max() > 0.0
        rows.append(f"| {st:g} | {eps:g} | {sigma:g} | {k:g} | {'yes' if touched else 'no'} | "
                    f"{res_s.e_wet:.4f} | {res_r.e_wet:.4f} | "
                    f"{1e3 * statistics.median(t_s):.0f} | {1e3 * statistics.median(t_r):.0f} | "
                    f"{ratio:.2f} | {res_s.steps}/{res_s.newton_iterations}/"
                    f"{res_s.lu_factorizations} | {res_r.steps}/{res_r.newton_iterations}/"
                    f"{res_r.lu_factorizations} |")
        print(rows[-1], flush=True)
    text = [
        "# Rough against smooth collisions: cost", "",
        f"`python benchmarks/bench_contact.py` (solver {SOLVER_VERSION}, {platform.machine()}, "
        f"{os.cpu_count()} cores, OPENBLAS_NUM_THREADS=1), standard preset, e_dry 0.97. CPU time "
        f"per collision, median of {REPEATS} alternated solves of each side; counts are "
        "steps/Newton iterations/LU factorisations. Target (issue 17): a rough collision at most "
        "2x the smooth one.", "",
        "| St | eps | roughness | k | touched | e_wet smooth | e_wet rough | smooth ms | rough ms "
        "| ratio | smooth counts | rough counts |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
        *rows, "",
        f"Median ratio {statistics.median(ratios):.2f}, largest {max(ratios):.2f}.", "",
        "Where the time goes (counts above): the rough film factorises its Newton matrix 3-6x "
        "as often (the contact's stiffness, which the chord iteration holds fixed, changes "
        "fast while the contact ring moves, so iterations stall and the Jacobian is rebuilt), "
        "each rebuild also forms the implicit derivatives dH/dP (an extra n x n x m product), "
        "and every residual solves the contact gap (m x m chord Newton). The target is missed; "
        "what would reach it: a factorisation kept across the contact's changes (a low-rank "
        "update of the contact nodes' rows, as the cavity's), and a contact law smooth at first "
        "touch (Greenwood-Williamson heights instead of one summit height).", ""]
    out.write_text("\n".join(text))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
