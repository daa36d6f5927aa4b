"""Pure functions of a sweep Dataset: validity masks, counts, and the critical Stokes number.

Stick or rebound: a collision "escapes" when the rebound carries the spheres back beyond the
start separation, ``x_e > x0`` (``ln_x_e_x0 > 0``). The critical Stokes number ``St_c(eps)`` is
where this first happens along each eps row of an (eps, St) plane of the store (one plane per
value combination of the store's other axes, :func:`planes`): bracketed by the last stuck and the first
escaped scene, and placed by linear interpolation of ``ln(x_e/x0)`` in ``ln St`` (the grid is
log-spaced and ``ln(x_e/x0)`` is smooth and changes sign there).
"""

from __future__ import annotations

import csv
import io
import math

import numpy as np

from .config import physics_from_json

__all__ = ["valid", "critical_stokes", "critical_stokes_csv", "planes", "extra_axes",
           "PlaneError", "critical_stokes_plane", "EXPERIMENT_ST_C", "EXPERIMENT_REFERENCE", "PLANE"]

# Solid spheres do not rebound from a wall in liquid below St of about 10 (St = m v0/(6 pi mu a^2),
# the same definition as ours: Joseph et al. 2001 write St = rho_p v D / (9 mu)).
EXPERIMENT_ST_C = 10.0
EXPERIMENT_REFERENCE = ("Joseph, Zenit, Hunt & Rosenwinkel, J. Fluid Mech. 433 (2001); "
                        "Gondret, Lance & Petit, Phys. Fluids 14 (2002)")

CSV_FIELDS = ("eps", "St_c", "St_stuck", "St_escaped", "transitions", "note")
PLANE = ("eps", "St")  # the plane of the classic figures and of St_c: rows eps, columns St


class PlaneError(ValueError):
    """The store has no (eps, St) plane: St or eps is neither an axis nor fixed."""


def valid(ds) -> np.ndarray:
    """Boolean mask of scenes stored as ok (``status == 1``), in the Dataset's dim order."""
    return np.asarray(ds["status"].values == 1)


def extra_axes(ds) -> tuple:
    """The store's axes other than St and eps, in store order."""
    return tuple(d for d in ds["status"].dims if d not in PLANE)


def planes(ds):
    """Yield ``(extra, plane)`` for every value combination of the axes other than St and eps:
    ``extra`` is ``{name: value}`` of those axes (empty for an (St, eps) store), ``plane`` the
    2-D Dataset with dims ``(eps, St)``. St or eps fixed by the sweep (``attrs
    ["fixed_physics"]``) becomes a length-1 axis.

    Raises
    ------
    PlaneError
        St or eps is neither an axis nor fixed.
    """
    import itertools

    fixed = physics_from_json(dict(ds.attrs.get("fixed_physics", {})))
    for name in PLANE:
        if name not in ds["status"].dims:
            if name not in fixed:
                raise PlaneError(f"the store has no {name} axis or fixed {name} (axes "
                                 f"{list(ds['status'].dims)}); the (eps, St) figures and St_c need "
                                 "both")
            ds = ds.expand_dims({name: [float(fixed[name])]})
    extra = extra_axes(ds)
    for values in itertools.product(*(range(ds.sizes[a]) for a in extra)):
        sel = dict(zip(extra, values))
        plane = ds.isel(sel).transpose(*PLANE, ...)
        yield {a: float(ds[a].values[i]) for a, i in sel.items()}, plane


def critical_stokes(ds) -> list[dict]:
    """St_c for every eps row of every (eps, St) plane of a sweep Dataset (:func:`planes`).

    Returns
    -------
    list of dict
        One per eps (ascending) and combination of the other axes (their values as keys first):
        ``eps``; ``St_c`` (NaN when the row does not change from stuck to
        escaped inside the grid); ``St_stuck``/``St_escaped``, the bracketing grid points;
        ``transitions``, the number of stuck/escaped changes along the row (1 for a clean
        threshold); ``note`` ("", "all escaped", "none escaped", "no valid scenes",
        "bracket spans failed or missing scenes").
    """
    rows = []
    for extra, plane in planes(ds):
        rows += critical_stokes_plane(plane, extra)
    return rows


def critical_stokes_plane(ds, extra: dict | None = None) -> list[dict]:
    """St_c per eps row of one (eps, St) plane (rows carry ``extra`` first)."""
    extra = extra or {}
    St = np.asarray(ds["St"].values, dtype=float)
    ok = valid(ds)
    esc = np.asarray(ds["escaped"].values, dtype=float)
    ln = np.asarray(ds["ln_x_e_x0"].values, dtype=float)
    rows = []
    for i, eps in enumerate(np.asarray(ds["eps"].values, dtype=float)):
        row = {**extra, "eps": float(eps), "St_c": math.nan, "St_stuck": math.nan,
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
    """The St_c table as CSV text (fixed formatting: same table, same bytes); the values of the
    store's other axes, if any, come first."""
    rows = list(rows)
    extra = [k for k in rows[0] if k not in CSV_FIELDS] if rows else []
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow([*extra, *CSV_FIELDS])
    for r in rows:
        w.writerow([*(f"{r[k]:.6g}" for k in extra), f"{r['eps']:.6g}", _g(r["St_c"]), _g(r["St_stuck"]), _g(r["St_escaped"]),
                    r["transitions"], r["note"]])
    return out.getvalue()


def _g(v) -> str:
    return "" if not math.isfinite(v) else f"{v:.5g}"
