"""What a rough collision costs against the smooth one at the same preset (issue 17's target: at
most 2x), alternated scene by scene in one process so both share the machine's load.

Scenes: the standard preset, St 10-100 x eps 1e-4 and 1e-5, roughness 0.5 and 1 x1 (a polished
steel ball on glass is about 0.6 x1, docs/model.md "Surface roughness"), asperity stiffness 2
and 20, e_dry 0.97; on the classic film, and on the cavitating film (JFO, Pi 1e-3) that the
scenes switch on for liquids whose tension crosses their vapour pressure, where the asperities
touch inside the cavity too (the cells whose gap stays implicit, docs/solver.md "Surface
roughness"). Each scene is solved ``REPEATS`` times on each side, alternately, after one warm-up
solve of each (compilation); the table gives the CPU-time medians, their ratio and the counters
of both.

``python benchmarks/bench_contact.py [--quick]`` (about a minute; ``make bench``) writes
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
FILMS = (("classic", {}), ("JFO, Pi 1e-3", dict(Pi=1e-3, cavitation="jfo")))
SCENES = [(film, st, eps, sigma, k) for film in FILMS for st in (10.0, 30.0, 100.0)
          for eps in (1e-4, 1e-5) for sigma, k in ((0.5, 20.0), (1.0, 2.0))]
TARGET = 2.0


def _cpu(physics):
    start = time.process_time()
    result = collide(physics)
    return time.process_time() - start, result


def _counts(res):
    return f"{res.steps}/{res.rejected_steps}/{res.newton_iterations}/{res.lu_factorizations}"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    scenes = SCENES[:2] if args.quick else SCENES
    out = Path("/tmp/contact.md") if args.quick else HERE / "contact.md"
    rows, ratios = [], {name: [] for name, _ in FILMS}
    for (film, extra), st, eps, sigma, k in scenes:
        smooth = Physics(St=st, eps=eps, **extra)
        rough = smooth.replace(roughness=sigma, asperity_stiffness=k, e_dry=0.97)
        _cpu(smooth), _cpu(rough)  # compile, fill caches
        t_s, t_r = [], []
        for _ in range(REPEATS):
            t, res_s = _cpu(smooth)
            t_s.append(t)
            t, res_r = _cpu(rough)
            t_r.append(t)
        if not (res_s.ok and res_r.ok):
            raise SystemExit(f"{film} St {st:g} eps {eps:g}: {res_s.status} / {res_r.status}")
        ratio = statistics.median(t_r) / statistics.median(t_s)
        ratios[film].append(ratio)
        touched = res_r.series["F_contact"].max() > 0.0
        rows.append(f"| {film} | {st:g} | {eps:g} | {sigma:g} | {k:g} | "
                    f"{'yes' if touched else 'no'} | {res_s.e_wet:.4f} | {res_r.e_wet:.4f} | "
                    f"{1e3 * statistics.median(t_s):.0f} | {1e3 * statistics.median(t_r):.0f} | "
                    f"{ratio:.2f} | {_counts(res_s)} | {_counts(res_r)} |")
        print(rows[-1], flush=True)
    summary = [f"- {film}: median ratio {statistics.median(r):.2f}, largest {max(r):.2f} "
               f"({sum(x <= TARGET for x in r)} of {len(r)} scenes within {TARGET:g}x)."
               for film, r in ratios.items() if r]
    text = [
        "# Rough against smooth collisions: cost", "",
        f"`python benchmarks/bench_contact.py` (solver {SOLVER_VERSION}, {platform.machine()}, "
        f"{os.cpu_count()} cores, OPENBLAS_NUM_THREADS=1), standard preset, e_dry 0.97. CPU time "
        f"per collision, median of {REPEATS} alternated solves of each side; counts are "
        "steps/rejected steps/Newton iterations/LU factorisations. Target (issue 17): a rough "
        f"collision at most {TARGET:g}x the smooth one.", "",
        "| film | St | eps | roughness | k | touched | e_wet smooth | e_wet rough | smooth ms "
        "| rough ms | ratio | smooth counts | rough counts |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
        *rows, "", *summary, "",
        "How: a rough film's unknown is the total surface load `T = P + p_a` (docs/solver.md, "
        "\"Surface roughness\"), so its gap is explicit and its Jacobian costs the smooth film's "
        "(solver 1.7 solved an implicit contact gap by Newton at every iterate and built the "
        "implicit derivatives with every Jacobian); and the contact law is smooth at first "
        "touch (summit heights spread to the tallest), so the contact's edge crossing the nodes "
        "no longer rejects steps (1.7: 58-529 rejections per rough collision against 6-11). "
        "Solver 1.7.0 measured here: 5-11x (median 8x) on the classic film. What remains is "
        "the extra steps while the asperities carry load, and in a cavity the cells that touch, "
        "whose gaps stay implicit (an m x m Newton per iterate, m of them).", ""]
    out.write_text("\n".join(text))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
