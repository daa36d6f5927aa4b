"""The wet restitution e_wet (at x_ref = x0) at eps = 1e-4, 1e-6, 1e-8 for St = 15, 30, 100, 500,
standard accuracy, direct solves; prints a markdown table (issue 12's closing numbers).

    python benchmarks/e_wet_table.py
"""

import math

from pipeline import environment  # noqa: F401  (single-threaded BLAS)
from solver import collide

STOKES = (15.0, 30.0, 100.0, 500.0)
EPS = (1e-4, 1e-6, 1e-8)


def legendre(st, rho_ratio=0.0):
    """Legendre et al.'s e/e_dry = exp(-35/St_L), St_L = St (1 + rho_f/(2 rho_p))."""
    return math.exp(-35.0 / (st * (1.0 + 0.5 * rho_ratio)))


def main():
    print("| St | " + " | ".join(f"eps = {e:g}" for e in EPS) + " | exp(-35/St) |")
    print("|---|" + "---|" * (len(EPS) + 1))
    for st in STOKES:
        cells = []
        for eps in EPS:
            c = collide(st, eps, accuracy="standard", save_profiles=False)
            cells.append(f"{c.e_wet:.4f}" if c.ok else c.status)
        print(f"| {st:g} | " + " | ".join(cells) + f" | {legendre(st):.4f} |", flush=True)


if __name__ == "__main__":
    main()
