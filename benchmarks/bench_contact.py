"""What a rough collision costs against the smooth one at the same preset (issue 17's target: at
most 2x), alternated scene by scene in one process so both share the machine's load.

Scenes: the standard preset, St 10-100 x eps 1e-4 and 1e-5, roughness 0.5 and 1 x1 (a polished
steel ball on glass is about 0.6 x1, docs/model.md "Surface roughness"), asperity stiffness 2
and 20, e_dry 0.97; on the classic film, and on the cavitating film (JFO, Pi 1e-3) that the
scenes switch on for liquids whose tension crosses their vapour pressure, where the asperities
touch inside the cavity too (the cells whose gap stays implicit, docs/solver.md "Surface
roughness"). Each scene is solved ``REPEATS`` times on each side in rounds, the order of the
sides rotated from round to round, after one warm-up round (compilation; benchmarks/harness.py);
the table gives the CPU-time medians, the median of the per-round ratios rough / smooth with
their range, and the counters of both.

``python benchmarks/bench_contact.py [--quick]`` (a few minutes) writes ``benchmarks/contact.md``
and ``contact.json`` (``--quick``: two scenes, written to /tmp). Against another commit,
alternated: ``make bench`` (``benchmarks/suite.py``).
"""

from __future__ import annotations

import argparse
import os
import statistics
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import harness  # noqa: E402
from solver import Physics, collide  # noqa: E402

HERE = Path(__file__).parent
REPEATS = 5
FILMS = (("classic", {}), ("JFO, Pi 1e-3", dict(Pi=1e-3, cavitation="jfo")))
SCENES = [(film, st, eps, sigma, k) for film in FILMS for st in (10.0, 30.0, 100.0)
          for eps in (1e-4, 1e-5) for sigma, k in ((0.5, 20.0), (1.0, 2.0))]
TARGET = 2.0


def _side(physics, last: dict, key: str):
    """One timed solve of ``physics``, keeping the result in ``last[key]``."""
    def once():
        return harness.time_call(lambda: last.__setitem__(key, collide(physics)))
    return once


def _counts(res):
    return f"{res.steps}/{res.rejected_steps}/{res.newton_iterations}/{res.lu_factorizations}"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    scenes = SCENES[:2] if args.quick else SCENES
    out = Path("/tmp/contact.md") if args.quick else HERE / "contact.md"
    load_start = harness.load_now()
    rows, ratios, records = [], {name: [] for name, _ in FILMS}, []
    for (film, extra), st, eps, sigma, k in scenes:
        smooth = Physics(St=st, eps=eps, **extra)
        rough = smooth.replace(roughness=sigma, asperity_stiffness=k, e_dry=0.97)
        last = {}
        runs = harness.alternate({"smooth": _side(smooth, last, "smooth"),
                                  "rough": _side(rough, last, "rough")}, REPEATS)
        res_s, res_r = last["smooth"], last["rough"]
        if not (res_s.ok and res_r.ok):
            raise SystemExit(f"{film} St {st:g} eps {eps:g}: {res_s.status} / {res_r.status}")
        cmp = harness.compare_runs(runs["rough"], runs["smooth"], ("cpu_s",))["cpu_s"]
        ratio = cmp["ratio"]["median"]
        ratios[film].append(ratio)
        touched = bool(res_r.series["F_contact"].max() > 0.0)
        records.append({"film": film, "St": st, "eps": eps, "roughness": sigma,
                        "asperity_stiffness": k, "touched": touched, "e_wet_smooth": res_s.e_wet,
                        "e_wet_rough": res_r.e_wet, "cpu_s": cmp,
                        "counts_smooth": _counts(res_s), "counts_rough": _counts(res_r)})
        t_s, t_r = cmp["baseline"]["median"], cmp["this"]["median"]
        rows.append(f"| {film} | {st:g} | {eps:g} | {sigma:g} | {k:g} | "
                    f"{'yes' if touched else 'no'} | {res_s.e_wet:.4f} | {res_r.e_wet:.4f} | "
                    f"{1e3 * t_s:.0f} | {1e3 * t_r:.0f} | "
                    f"{ratio:.2f} | {cmp['ratio']['min']:.2f}-{cmp['ratio']['max']:.2f} | "
                    f"{_counts(res_s)} | {_counts(res_r)} |")
        print(rows[-1], flush=True)
    doc = harness.write_json(out.with_suffix(".json"), {
        "repeats": REPEATS, "target": TARGET, "scenes": records}, load_start)
    summary = [f"- {film}: median ratio {statistics.median(r):.2f}, largest {max(r):.2f} "
               f"({sum(x <= TARGET for x in r)} of {len(r)} scenes within {TARGET:g}x)."
               for film, r in ratios.items() if r]
    text = [
        "# Rough against smooth collisions: cost", "",
        f"`python benchmarks/bench_contact.py`: {harness.describe(doc)}. Standard preset, e_dry "
        f"0.97. CPU time per collision, median of {REPEATS} rounds alternating the two sides; "
        "ratio: the median of the per-round ratios rough / smooth, with their range; counts are "
        "steps/rejected steps/Newton iterations/LU factorisations. Target (issue 17): a rough "
        f"collision at most {TARGET:g}x the smooth one.", "",
        "| film | St | eps | roughness | k | touched | e_wet smooth | e_wet rough | smooth ms "
        "| rough ms | ratio | rounds' ratios | smooth counts | rough counts |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
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
