"""Orders above 2: BDF2 (the presets up to solver 1.11.0) against the variable-order BDF up to
``--order`` (issue 30, item 1) at the preset's tolerance for it (``rtol`` times
``high_order_rtol_factor``, or ``--factor``), on the classic film at one preset, in one process.

For each scene (St x eps): the counts of both (accepted and rejected steps, Newton iterations,
LU factorisations), their CPU time alternated in rounds (``harness.alternate``: the median of
the per-round ratios and their range), and each one's time error: the distance to the same grid
integrated to ``REF_RTOL`` at the highest order (factor 1), on the rebound speed ``v_r`` and the
departure ``ln_x_e_x1``, which the integration gives. The closest approach ``h_m_x1`` is shown
beside them: it is read from the series by a parabola through the extreme step, an error of the step
spacing's cube that does not follow the method's order. The grid's own error is the same for
both and is not part of these numbers (benchmarks/accuracy.md gives it). A scene that never
hands over to the coupled solution (the rigid film alone: St 2, eps 1e-6) is left out.

Usage: ``python benchmarks/bench_order.py [--accuracy standard] [--order 5] [--factor F]
[--rounds 5] [--out benchmarks/order.md]`` (the JSON beside it).
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

import harness

REPO = Path(__file__).resolve().parent.parent
STOKES = (2.0, 5.0, 10.0, 30.0, 100.0, 300.0)
EPS = (1e-2, 1e-4, 1e-6)
REF_RTOL = 1e-8  # the time-converged reference: BDF2 at 1e-8 agrees with it to 1e-7 in v_r
OBSERVED = ("v_r", "ln_x_e_x1", "h_m_x1")
COUNTS = ("steps", "higher_order_steps", "rejected_steps", "newton_iterations",
          "lu_factorizations")


def scene(stokes, eps, accuracy, order, factor, rounds):
    """One scene: both runs' counts, observables and CPU times, and the reference's values."""
    from solver import Physics, collide

    physics = Physics(St=stokes, eps=eps)

    def run(k, rtol=None, f=None):
        return collide(physics, accuracy=accuracy, max_order=k, rtol=rtol,
                       high_order_rtol_factor=factor if f is None else f, save_profiles=False)

    ref = run(order, REF_RTOL, 1.0)
    sides = {f"k{k}": (lambda k=k: harness.time_call(lambda: run(k))) for k in (2, order)}
    times = harness.alternate(sides, rounds)
    row = {"St": stokes, "eps": eps, "ref": {o: getattr(ref, o) for o in OBSERVED},
           "ref_steps": ref.steps}
    for k in (2, order):
        c = run(k)
        row[f"k{k}"] = {**{n: getattr(c, n) for n in COUNTS},
                        **{o: getattr(c, o) for o in OBSERVED},
                        "error": {o: abs(getattr(c, o) - row["ref"][o]) for o in OBSERVED},
                        "cpu_s": [t["cpu_s"] for t in times[f"k{k}"]]}
    row["cpu_ratio"] = harness.compare(row[f"k{order}"]["cpu_s"], row["k2"]["cpu_s"])["ratio"]
    return row


def render(rows, meta, doc) -> str:
    k = meta["order"]
    head = (f"# Orders above 2 (`benchmarks/bench_order.py`)\n\n{harness.describe(doc)}\n\n"
            f"The classic film at the {meta['accuracy']} preset: BDF2 at the preset's rtol (k2, "
            f"the presets up to solver 1.11.0) against the variable-order BDF up to order {k} "
            f"(k{k}, `max_order={k}`) at {meta['factor']:g} times that rtol "
            "(`high_order_rtol_factor`), the same grid. Time error: the distance to the same "
            f"grid integrated to rtol {REF_RTOL:g} at order {k}. CPU: median of "
            f"{meta['rounds']} alternated rounds, the ratio k{k} / k2 per round (median and "
            "range).\n\n")
    lines = [f"| St | eps | steps k2 / k{k} | k{k} above order 2 | rejected | Newton | LU | "
             f"CPU k{k}/k2 (rounds) | v_r error k2 / k{k} | ln_x_e error k2 / k{k} | "
             f"h_m error k2 / k{k} |",
             "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        a, b, q = r["k2"], r[f"k{k}"], r["cpu_ratio"]
        lines.append(
            f"| {r['St']:g} | {r['eps']:g} | {a['steps']} / {b['steps']} | "
            f"{b['higher_order_steps']} | {a['rejected_steps']} / {b['rejected_steps']} | "
            f"{a['newton_iterations']} / {b['newton_iterations']} | "
            f"{a['lu_factorizations']} / {b['lu_factorizations']} | "
            f"{q['median']:.2f} ({q['min']:.2f}-{q['max']:.2f}) | "
            + " | ".join(f"{a['error'][o]:.1e} / {b['error'][o]:.1e}" for o in OBSERVED) + " |")
    steps = [r[f"k{k}"]["steps"] / r["k2"]["steps"] for r in rows]
    cpu = [r["cpu_ratio"]["median"] for r in rows]
    smaller = {o: sum(r[f"k{k}"]["error"][o] <= r["k2"]["error"][o] for r in rows)
               for o in OBSERVED}
    summary = (f"\n\nOver the {len(rows)} scenes: steps k{k}/k2 median "
               f"{statistics.median(steps):.2f} ({min(steps):.2f}-{max(steps):.2f}); CPU ratio "
               f"median {statistics.median(cpu):.2f} (scene medians {min(cpu):.2f}-{max(cpu):.2f});"
               f" the time error of k{k} no larger than BDF2's in "
               + ", ".join(f"{o} {n} of {len(rows)}" for o, n in smaller.items()) + ".\n")
    return head + "\n".join(lines) + summary


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--accuracy", default="standard", choices=("fast", "standard", "fine"))
    p.add_argument("--order", type=int, default=5, help="the highest order compared (3-5)")
    p.add_argument("--factor", type=float, default=None,
                   help="the tolerance above order 2 over rtol (default: the preset's)")
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--out", default=str(REPO / "benchmarks" / "order.md"))
    args = p.parse_args(argv)
    if not Path(args.out).parent.is_dir():  # fail before the runs, not after them
        p.error(f"--out {args.out}: its folder does not exist")
    from solver.settings import PRESETS

    factor = PRESETS[args.accuracy].high_order_rtol_factor if args.factor is None else args.factor
    load_start = harness.load_now()
    rows = [scene(st, eps, args.accuracy, args.order, factor, args.rounds)
            for eps in EPS for st in STOKES]
    rows = [r for r in rows if r["k2"]["steps"] > 0]  # a scene the rigid film solves alone
    meta = {"accuracy": args.accuracy, "order": args.order, "factor": factor,
            "rounds": args.rounds}
    doc = harness.save_results(args.out, {"meta": meta, "scenes": rows}, load_start)
    harness.save_report(args.out, render(rows, meta, doc))
    return 0


if __name__ == "__main__":
    sys.exit(main())
