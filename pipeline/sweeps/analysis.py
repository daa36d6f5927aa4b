"""Pure functions of a sweep Dataset: validity masks, counts, and the critical Stokes number.

Stick or rebound: a collision "escapes" when the rebound carries the spheres back beyond the
start separation, ``x_e > x0`` (``ln_x_e_x0 > 0``). The critical Stokes number ``St_c(eps)`` is
where this first happens along each eps row of the grid: bracketed by the last stuck and the first
escaped scene, and placed by linear interpolation of ``ln(x_e/x0)`` in ``ln St`` (the grid is
log-spaced and ``ln(x_e/x0)`` is smooth and changes sign there).
"""

from __future__ import annotations

import csv
import io
import math

import numpy as np

__all__ = ["valid", "critical_stokes", "critical_stokes_csv", "EXPERIMENT_ST_C",
           "EXPERIMENT_REFERENCE"]

# Solid spheres do not rebound from a wall in liquid below St of about 10 (St = m v0/(6 pi mu a^2),
# the same definition as ours: Joseph et al. 2001 write St = rho_p v D / (9 mu)).
EXPERIMENT_ST_C = 10.0
EXPERIMENT_REFERENCE = ("Joseph, Zenit, Hunt & Rosenwinkel, J. Fluid Mech. 433 (2001); "
                        "Gondret, Lance & Petit, Phys. Fluids 14 (2002)")

CSV_FIELDS = ("eps", "St_c", "St_stuck", "St_escaped", "transitions", "note")


def valid(ds) -> np.ndarray:
    """Boolean ``(eps, St)`` mask of scenes stored as ok (``status == 1``)."""
    return np.asarray(ds["status"].values == 1)


def critical_stokes(ds) -> list[dict]:
    """St_c for every eps row of a sweep Dataset.

    Returns
    -------
    list of dict
        One per eps (ascending): ``eps``; ``St_c`` (NaN when the row does not change from stuck to
        escaped inside the grid); ``St_stuck``/``St_escaped``, the bracketing grid points;
        ``transitions``, the number of stuck/escaped changes along the row (1 for a clean
        threshold); ``note`` ("", "all escaped", "none escaped", "no valid scenes",
        "bracket spans failed or missing scenes").
    """
    St = np.asarray(ds["St"].values, dtype=float)
    ok = valid(ds)
    esc = np.asarray(ds["escaped"].values, dtype=float)
    ln = np.asarray(ds["ln_x_e_x0"].values, dtype=float)
    rows = []
    for i, eps in enumerate(np.asarray(ds["eps"].values, dtype=float)):
        row = {"eps": float(eps), "St_c": math.nan, "St_stuck": math.nan,
               "St_escaped": math.nan, "transitions": 0, "note": ""}
        k = np.nonzero(ok[i] & np.isfinite(esc[i]))[0]
        if k.size == 0:
            row["note"] = "no valid scenes"
            rows.append(row)
            continue
        e = esc[i, k] > 0.5
        changes = np.nonzero(e[1:] != e[:-1])[0]
        row["transitions"] = int(changes.size)
        ups = [c for c in changes if not e[c] and e[c + 1]]
        if not ups:
            row["note"] = "all escaped" if e.all() else "none escaped"
            rows.append(row)
            continue
        a, b = k[ups[0]], k[ups[0] + 1]
        row["St_stuck"], row["St_escaped"] = float(St[a]), float(St[b])
        la, lb = ln[i, a], ln[i, b]
        if np.isfinite(la) and np.isfinite(lb) and la <= 0.0 < lb:
            w = -la / (lb - la)
            row["St_c"] = float(math.exp((1 - w) * math.log(St[a]) + w * math.log(St[b])))
        else:  # flags and logs disagree (should not happen): the geometric midpoint
            row["St_c"] = float(math.sqrt(St[a] * St[b]))
        if b - a > 1:
            row["note"] = "bracket spans failed or missing scenes"
        rows.append(row)
    return rows


def critical_stokes_csv(rows) -> str:
    """The St_c table as CSV text (fixed formatting: same table, same bytes)."""
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(CSV_FIELDS)
    for r in rows:
        w.writerow([f"{r['eps']:.6g}", _g(r["St_c"]), _g(r["St_stuck"]), _g(r["St_escaped"]),
                    r["transitions"], r["note"]])
    return out.getvalue()


def _g(v) -> str:
    return "" if not math.isfinite(v) else f"{v:.5g}"
