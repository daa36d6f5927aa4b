"""Figures of a sweep store (a pure function of the store: nothing is computed, same store -> same
bytes).

- Figure 12: maximum rebound velocity ``v_r/v0`` against St, one curve per eps; next to it
  (12b) the wet restitution ``e_wet`` (what DEM codes and experiments call e) the same way, and
  ``e_wet`` over the experimental curve of sphere-wall collisions in liquids
  (``draw_experiments``);
- Figure 13: closest approach ``h_m/x1`` against St; Figure 14: equilibrium separation ``x_e/x1``
  against St (drawn from ``ln_x_e_x1``: ``x_e`` can overflow a float at large St), with each
  eps's start separation ``x0/x1 = eps^-0.4`` for reference (``x_e > x0``: the spheres escape);
- the same three quantities as maps over the (St, eps) plane;
- stick or rebound: the map of ``escaped`` with the critical Stokes number St_c(eps) against the
  experimental St ~ 10, and the St_c table as CSV;
- a store with a further physics axis declared in ``AXES`` gets that group as the curve
  parameter, with the classic film on the same axes (``axis_figures``): with ``Pi`` (cavitation),
  per eps ``v_r``, ``ln(x_e/x0)`` and ``e_wet`` against St, one curve per Pi, the classic film at
  Pi = inf (``cavitation_eps=...``), and ``St_c`` against Pi per eps (``critical_stokes_vs_Pi``);
  with ``beta`` (piezoviscous liquid), per eps ``v_r``, ``h_m``, ``ln(x_e/x0)`` and the peak
  viscosity on approach against St, one curve per beta, the classic film at beta = 0
  (``piezoviscous_eps=...``), and ``St_c`` against beta per eps (``critical_stokes_vs_beta``).

Every figure is drawn on an (eps, St) plane of the store (``analysis.planes``: St or eps fixed by
the sweep is a plane one row or column wide). A store with further axes gets one set of figures
per value combination of them, the file names suffixed with the values (``_Pi=0.001``); the CSV
holds every plane, those values in its first columns.

Maps are drawn in log10 coordinates (linear axes labelled in powers of ten): cell edges are the
midpoints of neighbouring log10 grid values, and contours are interpolated in log coordinates
(matplotlib's ``shading="nearest"`` would take arithmetic edges, and ``contour`` on log axes
interpolates in data coordinates, so a level between decades lands in the wrong place). Failed
scenes are cross-hatched in red on white (visible on any colour map) and counted in the legend;
scenes not run are left grey.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from solver.physics import Physics

from ..sweeps.analysis import (EXPERIMENT_REFERENCE, EXPERIMENT_ST_C, critical_stokes,
                               critical_stokes_csv, planes, valid)
from ..sweeps.config import physics_from_json
from ..writes import claim, retire

__all__ = ["render_all", "update_figures", "fingerprint", "FIGURES", "axis_figures", "AXES"]

FIGURES = ("fig12_rebound_velocity", "fig12b_wet_restitution", "fig13_closest_approach",
           "fig14_equilibrium_separation", "map_rebound_velocity", "map_closest_approach",
           "map_equilibrium_separation", "stick_or_rebound", "wet_restitution_experiments")
CSV_NAME = "critical_stokes.csv"
from .stamp import STAMP_NAME  # noqa: E402  (what the figures in a folder were drawn from)
FORMATS = ("png", "pdf")
DPI = 150
FAILED_COLOR = "#d62728"
NOT_RUN_COLOR = "#d9d9d9"
# reproducible bytes: no timestamps or version strings in the files, fixed SVG hash salt
_METADATA = {"png": {"Software": None},
             "pdf": {"Creator": None, "Producer": None, "CreationDate": None}}
_RC = {"svg.hashsalt": "ehd-collision", "figure.dpi": DPI, "font.size": 9,
       "axes.titlesize": 10, "legend.fontsize": 8}


def render_all(ds, out) -> list:
    """Render every sweep figure of ``ds`` into ``out``; return the written paths.

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep store (``pipeline.open_results``).
    out : str or Path
        Output folder (created).
    """
    import matplotlib
    import matplotlib.style

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    ds = ds.load()
    paths = []
    draws = dict(zip(FIGURES, (_fig12, _fig12b, _fig13, _fig14, _map_vr, _map_hm, _map_xe,
                               _stick_or_rebound, _experiments)))
    # the default style, not the user's matplotlibrc: the figures depend on the store only
    with matplotlib.style.context("default"), matplotlib.rc_context(_RC):
        for extra, plane in planes(ds):
            for name, draw in draws.items():
                fig = draw(plane)
                _footer(fig, plane, extra)
                for fmt in FORMATS:
                    path = out / f"{name}{_suffix(extra)}.{fmt}"
                    fig.savefig(claim(path), format=fmt, dpi=DPI, metadata=_METADATA[fmt])
                    paths.append(path)
        for name, draw in axis_figures(ds):
            fig = draw()
            for fmt in FORMATS:
                path = out / f"{name}.{fmt}"
                fig.savefig(claim(path), format=fmt, dpi=DPI, metadata=_METADATA[fmt])
                paths.append(path)
    csv_path = out / CSV_NAME
    claim(csv_path).write_text(critical_stokes_csv(critical_stokes(ds)))
    paths.append(csv_path)
    return paths


def fingerprint(ds) -> str:
    """sha256 of everything the figures depend on: the store's data, coordinates and attrs, the
    figure code and the matplotlib version."""
    import hashlib
    import json

    import matplotlib

    h = hashlib.sha256()
    package = Path(__file__).resolve().parent.parent
    for module in (Path(__file__).resolve(), package / "sweeps" / "analysis.py"):
        h.update(module.read_bytes())
    h.update(matplotlib.__version__.encode())
    h.update(json.dumps(ds.attrs, sort_keys=True, default=str).encode())
    for name in sorted(ds.variables):
        values = np.asarray(ds[name].values)
        h.update(f"{name}|{values.dtype}|{values.shape}|".encode())
        if values.dtype.kind in "OTU":  # strings: no fixed-width buffer to hash
            h.update("\0".join(map(str, values.ravel())).encode())
        else:
            h.update(np.ascontiguousarray(values).tobytes())
    return h.hexdigest()


def update_figures(ds, out, store=None, state=None) -> tuple[list, bool]:
    """Render the figures of ``ds`` into ``out`` unless that folder already holds them for the
    same store contents and figure code (a rerun of ``make sweep`` with nothing new then takes a
    second, not the ten a full render needs). ``state``: the file state (``stamp.store_state``)
    of the store ``ds`` was read from, taken before it was read, which the stamp records
    (``stamp.up_to_date`` checks it without reading the store); ``store``: that store's path, its
    state taken now (for a ``ds`` not read yet). Returns ``(paths, rendered)``."""
    from .stamp import read_stamp, stamp_text, store_state

    out = Path(out)
    if state is None and store is not None:
        state = store_state(store)  # before the read below: a conservative key
    ds = ds.load()
    key = fingerprint(ds)
    stamp = out / STAMP_NAME
    expected = [out / f"{n}{_suffix(extra)}.{f}" for extra, _ in planes(ds) for n in FIGURES
                for f in FORMATS] + [out / f"{n}.{f}" for n, _ in axis_figures(ds)
                                     for f in FORMATS] + [out / CSV_NAME]
    last = read_stamp(out)
    if last.get("fingerprint") == key and all(p.is_file() for p in expected):
        if state is not None:  # the same figures: record the store's file state for next time
            claim(stamp).write_text(stamp_text(key, state, expected))
        return expected, False
    out.mkdir(parents=True, exist_ok=True)
    # a render cut short must not leave a valid stamp behind (in a guarded_dir the old figures
    # and stamp stay as they were); the figures of the last render that this one does not draw
    # (a store that gained an axis names them anew) go with it
    for name in last.get("files") or []:
        if isinstance(name, str) and out / os.path.basename(name) not in expected:
            retire(out / os.path.basename(name))
    retire(stamp)
    paths = render_all(ds, out)
    claim(stamp).write_text(stamp_text(key, state, expected))
    return paths, True


# ---- helpers --------------------------------------------------------------------------------------
def _figure(figsize=(6.0, 4.2)):
    from matplotlib.figure import Figure

    return Figure(figsize=figsize, layout="constrained")


def _suffix(extra: dict) -> str:
    """File-name suffix of the plane at ``extra`` (values of the store's other axes)."""
    return "".join(f"_{k}={v:g}" if isinstance(v, float) else f"_{k}={v}" for k, v in extra.items())


def _footer(fig, ds, extra: dict | None = None) -> None:
    a = ds.attrs
    where = "".join(f", {k} = {v:g}" if isinstance(v, float) else f", {k} = {v}"
                    for k, v in (extra or {}).items())
    fig.get_layout_engine().set(rect=(0.0, 0.03, 1.0, 0.97))  # keep a strip for the footer
    fig.text(0.995, 0.004, f"sweep {a.get('sweep_name', '?')}, solver {a.get('solver_version', '?')}"
             f", accuracy {a.get('accuracy', '?')}{where}", ha="right", va="bottom", fontsize=6,
             color="0.45")


def _eps_label(eps: float) -> str:
    k = math.log10(eps)
    if abs(k - round(k)) < 1e-9:
        return rf"$\varepsilon = 10^{{{int(round(k))}}}$"
    return rf"$\varepsilon = {eps:.3g}$"


def _eps_colors(n):
    """Colours of ``n`` eps values in ascending order (the store's): the smallest eps darkest.
    Every figure with a curve per eps takes its colours from here, by the eps's rank."""
    import matplotlib

    cmap = matplotlib.colormaps["viridis"]
    return [cmap(x) for x in (np.linspace(0.0, 0.9, n) if n > 1 else [0.0])]


def eps_colors(eps_values) -> list:
    """The colour of each of ``eps_values`` (any order): its rank among them, as in Figs. 12-14."""
    order = np.argsort(np.asarray(eps_values, dtype=float))
    ranked = _eps_colors(len(order))
    colors = [None] * len(order)
    for rank, i in enumerate(order):
        colors[i] = ranked[rank]
    return colors


def _legend_outside(ax, **kwargs):
    """The legend right of the axes, never over the data."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False, borderaxespad=0.0,
              **kwargs)


def _failed(ds) -> np.ndarray:
    return np.asarray(ds["status"].values >= 2)


def _not_run(ds) -> np.ndarray:
    return np.asarray(ds["status"].values == 0)


def _field(ds, name) -> np.ndarray:
    """Values where the scene is ok, NaN elsewhere."""
    values = np.asarray(ds[name].values, dtype=float)
    return np.where(valid(ds), values, np.nan)


def _log10_x_e(ds) -> np.ndarray:
    return _field(ds, "ln_x_e_x1") / math.log(10.0)


def _curves(ds, y, ax, ylabel, *, logy=False, title=""):
    """One curve per eps against St (log axis); failed scenes marked under the curves."""
    St = ds["St"].values
    eps = ds["eps"].values
    failed = _failed(ds)
    colors = _eps_colors(eps.size)
    # largest eps first in the legend, as in the classic figures
    for i in range(eps.size - 1, -1, -1):
        ax.plot(St, y[i], color=colors[i], lw=1.3, marker="o", ms=2.0, label=_eps_label(eps[i]))
    ax.set_xscale("log")
    if logy and np.any(np.isfinite(y) & (y > 0)):  # a plane with no finished scene has none
        ax.set_yscale("log")
    if not np.isfinite(y).any():
        ax.text(0.5, 0.5, "no finished scene in this plane", transform=ax.transAxes,
                ha="center", va="center", color="0.4")
    ax.set_xlabel(r"Stokes number $St = m v_0 / (6 \pi \mu a^2)$")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="major", lw=0.4, alpha=0.5)
    if failed.any():
        rows, cols = np.nonzero(failed)
        ax.plot(St[cols], np.zeros(cols.size), ls="none", marker="x", color=FAILED_COLOR, ms=6,
                transform=ax.get_xaxis_transform(), clip_on=False,
                label=f"failed scene ({cols.size})")
    _legend_outside(ax)
    return ax


_CURVES_SIZE = (7.2, 4.2)  # a curve per eps, the legend right of the axes


def _fig12(ds):
    fig = _figure(_CURVES_SIZE)
    ax = fig.add_subplot()
    _curves(ds, _field(ds, "v_r"), ax, r"maximum rebound velocity $v_r / v_0$",
            title="Fig. 12: rebound velocity")
    ax.set_ylim(bottom=0.0)
    return fig


def _fig12b(ds):
    fig = _figure(_CURVES_SIZE)
    ax = fig.add_subplot()
    _curves(ds, _field(ds, "e_wet"), ax, r"wet restitution $e_{wet}$ (at $x_0$)",
            title="Fig. 12b: wet coefficient of restitution")
    ax.set_ylim(0.0, 1.0)
    return fig


# Experiments (sphere on a wall in liquids): e/e_dry = exp(-35/St_L) with Legendre's
# St_L = St (1 + rho_f/(2 rho_p)) (Legendre et al. 2006); no rebound below St ~ 10 (Joseph et al.
# 2001; Gondret et al. 2002); e near the dry value above St ~ 500 (Joseph et al. 2001).
EXPERIMENT_CURVE = ("Legendre, Zenit, Daniel & Guiraud, Chem. Eng. Sci. 61 (2006): "
                    "e/e_dry = exp(-35/St_L)")
LEGENDRE_C = 35.0
# density ratios rho_f/rho_p spanning the experiments' solids in liquids (steel in glycerol-water
# ~0.15, glass in water ~0.4): the experimental curve in our St moves by this much
DENSITY_RATIOS = (0.15, 0.4)


def legendre(stokes, density_ratio):
    """The experimental curve ``exp(-35/St_L)`` at our (= the experimenters') St."""
    return np.exp(-LEGENDRE_C / (np.asarray(stokes, float) * (1.0 + 0.5 * density_ratio)))


def draw_experiments(ax, stokes, curves: dict, colors=None):
    """Model ``e_wet(St)`` (``curves``: label -> values on ``stokes``) over the experiments;
    ``colors``, one per curve, default the eps colours of Figs. 12-14 for curves given from the
    largest eps to the smallest (``eps_colors``). The legend goes below the axes."""
    st = np.geomspace(1.0, 3000.0, 400)
    lo, hi = (legendre(st, r) for r in DENSITY_RATIOS)
    ax.fill_between(st, lo, hi, color="0.8", lw=0,
                    label=r"experiments' correlation (not data): $e/e_{dry} = e^{-35/St_L}$ "
                          r"(Legendre et al. 2006), $\rho_f/\rho_p$ = "
                          + f"{DENSITY_RATIOS[0]:g}-{DENSITY_RATIOS[1]:g}")
    ax.axvline(10.0, color="0.3", ls="--", lw=0.9,
               label="no rebound below St ~ 10 (Joseph et al. 2001; Gondret et al. 2002)")
    ax.axvspan(500.0, 3000.0, color="0.93", lw=0, label="e near e_dry (St > 500, Joseph et al.)")
    if colors is None:
        colors = _eps_colors(len(curves))[::-1]
    for (label, y), color in zip(curves.items(), colors):
        ax.plot(stokes, y, color=color, lw=1.4, marker="o", ms=2.0, label=label)
    ax.set_xscale("log")
    ax.set_xlim(1.0, 3000.0)
    ax.set_ylim(0.0, 1.05)
    ax.set_xlabel(r"Stokes number $St = m v_0/(6\pi\mu a^2) = \rho_p d v_0 / (9 \mu)$ (sphere on a wall)")
    ax.set_ylabel(r"$e_{wet}$ (model, $e_{dry} = 1$) and $e/e_{dry}$ (experiments)")
    ax.grid(True, which="major", lw=0.4, alpha=0.5)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, frameon=False,
              fontsize=6.5)


def _experiments(ds):
    fig = _figure((6.4, 5.6))
    ax = fig.add_subplot()
    eps = ds["eps"].values
    e = _field(ds, "e_wet")
    order = range(eps.size - 1, -1, -1)  # largest eps first in the legend, as in Fig. 12
    colors = eps_colors(eps)
    curves = {"model " + _eps_label(eps[i]): e[i] for i in order}
    draw_experiments(ax, ds["St"].values, curves, colors=[colors[i] for i in order])
    ax.set_title("Wet restitution: model against experiments")
    return fig


def _fig13(ds):
    fig = _figure(_CURVES_SIZE)
    ax = fig.add_subplot()
    _curves(ds, _field(ds, "h_m_x1"), ax, r"closest approach $h_m / x_1$", logy=True,
            title="Fig. 13: closest approach of the deformed surfaces")
    return fig


def _power_formatter():
    from matplotlib.ticker import FuncFormatter

    return FuncFormatter(lambda v, _: rf"$10^{{{v:g}}}$")


def _fig14(ds):
    """Two panels on one St axis: every value (x_e grows like exp(St) past escape, to 1e37 at
    St = 100), and near contact (up to three decades above the largest x0/x1), where the stick
    region's physics is."""
    from matplotlib.ticker import MaxNLocator

    fig = _figure((7.2, 6.6))
    full, near = fig.subplots(2, 1, sharex=True, height_ratios=(1.0, 1.6))
    y = _log10_x_e(ds)
    colors = _eps_colors(ds.sizes["eps"])
    _curves(ds, y, full, r"$x_e / x_1$ (all values)", title="Fig. 14: equilibrium separation")
    _curves(ds, y, near, r"equilibrium separation $x_e / x_1$")
    near.get_legend().remove()  # one legend, beside the upper panel
    full.set_xlabel("")
    for ax in (full, near):
        for i, eps in enumerate(ds["eps"].values):  # x0/x1 = eps^-0.4: above it they escape
            ax.axhline(-0.4 * math.log10(eps), color=colors[i], lw=0.8, ls=":")
        ax.yaxis.set_major_formatter(_power_formatter())
    full.yaxis.set_major_locator(MaxNLocator(integer=True, nbins=6))
    near.yaxis.set_major_locator(MaxNLocator(integer=True, nbins=8))
    near.text(0.01, 0.99, r"dotted: start separation $x_0/x_1 = \varepsilon^{-2/5}$ (above it "
              "the spheres escape)", transform=near.transAxes, va="top", fontsize=7, color="0.3")
    finite = y[np.isfinite(y)]
    if finite.size:
        top = max(-0.4 * math.log10(float(ds["eps"].values.min())), 0.0) + 3.0
        if finite.max() > top:
            near.set_ylim(min(float(finite.min()), 0.0) - 0.5, top)
            full.axhspan(min(float(finite.min()), 0.0) - 0.5, top, color="0.92", lw=0, zorder=0)
            full.text(0.01, 0.97, "shaded: the range of the lower panel",
                      transform=full.transAxes, va="top", fontsize=7, color="0.3")
    return fig


def _edges(log_centres: np.ndarray) -> np.ndarray:
    """Cell edges in log10 coordinates: midpoints between centres, half a step beyond the ends
    (half a decade for a single point)."""
    c = np.asarray(log_centres, dtype=float)
    if c.size == 1:
        return np.array([c[0] - 0.5, c[0] + 0.5])
    mid = 0.5 * (c[1:] + c[:-1])
    return np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])


def _mark_failed(ax, ex, ey, failed):
    """Failed cells: white with a red cross-hatch, unmistakable on any colour map."""
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Rectangle

    rows, cols = np.nonzero(failed)
    if rows.size:
        boxes = [Rectangle((ex[j], ey[i]), ex[j + 1] - ex[j], ey[i + 1] - ey[i])
                 for i, j in zip(rows, cols)]
        ax.add_collection(PatchCollection(boxes, facecolor="white", edgecolor=FAILED_COLOR,
                                          hatch="xxx", linewidth=0.0))


def _failed_handle(failed):
    from matplotlib.patches import Patch

    return Patch(facecolor="white", edgecolor=FAILED_COLOR, hatch="xxx",
                 label=f"failed ({int(failed.sum())})")


def _log_axes(ax, ds):
    """Axes in log10 St, log10 eps with ticks labelled as numbers."""
    from matplotlib.ticker import FixedLocator, FuncFormatter, MaxNLocator

    lx = np.log10(ds["St"].values)
    nice = np.array([0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 10000])
    ticks = np.log10(nice[(nice >= 10 ** lx.min() / 1.2) & (nice <= 10 ** lx.max() * 1.2)])
    ax.xaxis.set_major_locator(FixedLocator(ticks))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{10 ** v:g}"))
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.yaxis.set_major_formatter(_power_formatter())
    ax.set_xlabel(r"Stokes number $St$ (log scale)")
    ax.set_ylabel(r"elasticity parameter $\varepsilon$ (log scale)")


def _map(ds, z, title, cbar_label, levels, *, cbar_power=False, cmap="viridis", norm=None,
         cbar_ticks=None):
    """A (St, eps) map of ``z`` (NaN where not ok) with contours, failed and missing cells."""
    import matplotlib
    from matplotlib.patches import Patch

    fig = _figure((6.4, 4.4))
    ax = fig.add_subplot()
    ax.set_facecolor(NOT_RUN_COLOR)  # cells not run stay uncovered
    lx, ly = np.log10(ds["St"].values), np.log10(ds["eps"].values)
    ex, ey = _edges(lx), _edges(ly)
    zm = np.ma.masked_invalid(z)
    cm = matplotlib.colormaps[cmap]
    mesh = ax.pcolormesh(ex, ey, zm, cmap=cm, norm=norm, shading="flat")
    failed = _failed(ds)
    _mark_failed(ax, ex, ey, failed)
    if ly.size > 1 and lx.size > 1 and np.isfinite(z).sum() >= 4:
        finite = z[np.isfinite(z)]
        lv = [v for v in levels if finite.min() < v < finite.max()]
        if lv:
            cs = ax.contour(lx, ly, zm, levels=lv, colors="white", linewidths=0.8,
                            linestyles="solid")
            ax.clabel(cs, fmt=(lambda v: f"$10^{{{v:g}}}$") if cbar_power else "%g", fontsize=7)
    cb = fig.colorbar(mesh, ax=ax, spacing="uniform" if cbar_ticks is not None else
                      "proportional")
    cb.set_label(cbar_label)
    if cbar_power:
        finite = z[np.isfinite(z)]
        if cbar_ticks is not None:
            cb.set_ticks([v for v in cbar_ticks if float(v).is_integer()])
        elif finite.size:
            cb.set_ticks([v for v in levels if finite.min() <= v <= finite.max()])
        cb.formatter = _power_formatter()
        cb.update_ticks()
    _log_axes(ax, ds)
    ax.set_xlim(ex[0], ex[-1])
    ax.set_ylim(ey[0], ey[-1])
    ax.set_title(title)
    handles = [_failed_handle(failed),
               Patch(color=NOT_RUN_COLOR, label=f"not run ({int(_not_run(ds).sum())})")]
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(0.0, -0.13), ncol=2,
              frameon=False)
    return fig


def _map_vr(ds):
    return _map(ds, _field(ds, "v_r"), r"rebound velocity $v_r/v_0$", r"$v_r / v_0$",
                levels=[0.01, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9])


def _map_hm(ds):
    z = np.log10(_field(ds, "h_m_x1"))
    return _map(ds, z, r"closest approach $h_m/x_1$", r"$h_m / x_1$",
                levels=[-0.5, 0, 0.5, 1, 1.5, 2, 2.5, 3], cbar_power=True,
                cmap="magma")


# x_e/x1 spans ~1e-1 .. 1e37 on the paper grid: coloured in bands of log10(x_e/x1), a decade
# wide or half a decade near contact (the stick region) and wider where the spheres have escaped,
# each band one step of the colour bar, evenly spaced whatever its width
XE_BANDS = (-2.0, -1.0, -0.5, 0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 10.0, 20.0, 30.0, 40.0)


def _map_xe(ds):
    import matplotlib
    from matplotlib.colors import BoundaryNorm

    z = _log10_x_e(ds)
    norm = BoundaryNorm(XE_BANDS, matplotlib.colormaps["cividis"].N, extend="both")
    return _map(ds, z, r"equilibrium separation $x_e/x_1$", r"$x_e / x_1$",
                levels=[-1, 0, 1, 2, 5, 10, 20, 30], cbar_power=True, cmap="cividis", norm=norm,
                cbar_ticks=XE_BANDS)


def _stick_or_rebound(ds):
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    from matplotlib.figure import Figure

    fig = Figure(figsize=(10.0, 4.4), layout="constrained")
    ax, ax2 = fig.subplots(1, 2, width_ratios=[1.35, 1.0])
    ax.set_facecolor(NOT_RUN_COLOR)
    lx, ly = np.log10(ds["St"].values), np.log10(ds["eps"].values)
    ex, ey = _edges(lx), _edges(ly)
    esc = _field(ds, "escaped")
    stick_c, escape_c = "#9ecae1", "#fdae6b"
    ax.pcolormesh(ex, ey, np.ma.masked_invalid(esc), cmap=ListedColormap([stick_c, escape_c]),
                  vmin=0, vmax=1, shading="flat")
    failed = _failed(ds)
    _mark_failed(ax, ex, ey, failed)
    rows = critical_stokes(ds)  # ds is one plane here
    st_c = np.array([r["St_c"] for r in rows])
    eps = np.array([r["eps"] for r in rows])
    ok = np.isfinite(st_c)
    ax.plot(np.log10(st_c[ok]), np.log10(eps[ok]), "k-o", ms=3.5, lw=1.2,
            label=r"$St_c(\varepsilon)$ (interpolated)")
    if lx.min() <= math.log10(EXPERIMENT_ST_C) <= lx.max():
        ax.axvline(math.log10(EXPERIMENT_ST_C), color="k", ls="--", lw=1.0,
                   label=r"experiments: no rebound below $St \approx 10$")
    _log_axes(ax, ds)
    ax.set_xlim(ex[0], ex[-1])
    ax.set_ylim(ey[0], ey[-1])
    ax.set_title(r"stick or rebound: does the rebound carry the spheres beyond $x_0$?")
    handles = [Patch(color=stick_c, label=r"stick ($x_e < x_0$)"),
               Patch(color=escape_c, label=r"rebound ($x_e > x_0$)"),
               _failed_handle(failed),
               Patch(color=NOT_RUN_COLOR, label=f"not run ({int(_not_run(ds).sum())})")]
    lines, labels = ax.get_legend_handles_labels()
    ax.legend(handles=handles + lines, loc="upper left", bbox_to_anchor=(0.0, -0.13), ncol=3,
              frameon=False)

    ax2.semilogx(eps[ok], st_c[ok], "k-o", ms=3.5, lw=1.2, label=r"model $St_c(\varepsilon)$")
    ax2.axhline(EXPERIMENT_ST_C, color="k", ls="--", lw=1.0,
                label=r"experiments, $St \approx 10$")
    ax2.set_xlabel(r"elasticity parameter $\varepsilon$")
    ax2.set_ylabel(r"critical Stokes number $St_c$")
    ax2.set_title("critical Stokes number")
    ax2.grid(True, which="major", lw=0.4, alpha=0.5)
    ax2.set_ylim(bottom=0.0)
    if ok.any():
        top = max(float(np.nanmax(st_c)), EXPERIMENT_ST_C)
        ax2.set_ylim(0.0, 1.15 * top)
    ax2.text(0.02, 0.02, "experiments: " + EXPERIMENT_REFERENCE.replace("; ", ";\n"),
             transform=ax2.transAxes, fontsize=6, color="0.3", va="bottom", wrap=True)
    ax2.legend(loc="upper right", frameon=False)
    return fig


# ---- a store with a further physics axis (Pi, beta): that group as the curve parameter ----------
@dataclass(frozen=True)
class Panel:
    """One panel of a per-eps figure: ``variable`` against St, one curve per value of the axis."""

    variable: str
    label: str
    log: bool = False  # log y axis
    bottom: float | None = None  # fixed lower y limit
    top: float | None = None  # fixed upper y limit (with ``bottom``)
    # a dotted horizontal line (ln(x_e/x0) = 0: the threshold), or a function giving it (read
    # when drawn: the solver's solidification level is defined beside its compiled code)
    reference: float | object | None = None
    reference_label: str = ""  # written on that line; "{reference_exponent}": log10 of it

    def reference_value(self) -> float | None:
        return self.reference() if callable(self.reference) else self.reference
    window: tuple | None = None  # (floor, top): y shown from max(lowest, floor) - 0.5 up to top
    cap: float | None = None  # the axis stops here when a value passes it (a note says how far)


@dataclass(frozen=True)
class AxisFigures:
    """The figures of a store with the physics axis ``axis`` (a field of ``solver.Physics``): per
    eps the ``panels`` against St with a curve per value of the axis (``{name}_eps=...``), and St_c
    against the axis with a curve per eps (``critical_stokes_vs_{axis}``). The axis value of the
    classic film (``classic``) is drawn black dashed on the same axes. Another physics axis gets
    its figures by one more entry in ``AXES``."""

    axis: str
    name: str  # file-name stem of the per-eps figure
    symbol: str  # TeX, e.g. r"\Pi"
    classic: float  # the axis value at which the physics is off (the classic film)
    classic_tex: str  # that value in TeX
    log: bool  # log-spaced values: a log axis, powers of ten in the labels
    axis_label: str  # x label of the St_c figure
    panels: tuple
    title: str  # suptitle of the per-eps figure, filled with {eps} and the fields of Physics
    st_c_title: str
    figsize: tuple = (13.0, 4.2)
    grid: tuple = (1, 3)  # rows, columns of the panels

    @property
    def st_c_name(self) -> str:
        return f"critical_stokes_vs_{self.axis}"

    def label(self, v: float) -> str:
        if v == self.classic:
            return rf"classic film (${self.symbol} = {self.classic_tex}$)"
        k = math.log10(v) if self.log and v > 0 else math.nan
        if math.isfinite(k) and abs(k - round(k)) < 1e-9:
            return rf"${self.symbol} = 10^{{{int(round(k))}}}$"
        return rf"${self.symbol} = {v:.3g}$"

    def styles(self, values):
        """Colour, line style and width per value: the others along plasma, the farthest from the
        classic film darkest; the classic film black dashed."""
        import matplotlib

        cmap = matplotlib.colormaps["plasma"]
        others = [v for v in values if v != self.classic]
        others.sort(reverse=bool(others) and self.classic < min(others))
        shade = dict(zip(others, np.linspace(0.0, 0.85, len(others)) if len(others) > 1 else [0.0]))
        return [("k", "--", 1.6) if v == self.classic else (cmap(shade[v]), "-", 1.2)
                for v in values]


def _solid_viscosity_ratio() -> float:
    from solver.collision import SOLID_VISCOSITY_RATIO

    return SOLID_VISCOSITY_RATIO


_V_R = Panel("v_r", r"maximum rebound velocity $v_r/v_0$", bottom=0.0)
_LN_X_E = Panel("ln_x_e_x0", r"equilibrium separation $\ln(x_e/x_0)$ ($> 0$: rebound)",
                reference=0.0, window=(-20.0, 10.0))  # ln(x_e/x0) grows ~ St past escape
AXES = {a.axis: a for a in (
    AxisFigures("Pi", "cavitation", r"\Pi", math.inf, r"\infty", True,
                r"cavitation number $\Pi = (p_{amb} - p_{cav}) x_1^2 / (\mu a v_0)$",
                (_V_R, _LN_X_E, Panel("e_wet", r"wet restitution $e_{wet}$ (at $x_0$)", bottom=0.0,
                                      top=1.0)),
                "Cavitation (Reynolds floor $P \\geq -\\Pi$) at {eps}",
                r"stick-or-rebound threshold against the cavitation number"),
    AxisFigures("beta", "piezoviscous", r"\beta", 0.0, "0", False,
                r"piezoviscous number $\beta = \alpha \mu_0 a v_0 / x_1^2$",
                (_V_R, Panel("h_m_x1", r"closest approach $h_m/x_1$", log=True), _LN_X_E,
                 Panel("viscosity_ratio_max_approach",
                       r"peak viscosity on approach $\mu_{max}/\mu_0$", log=True,
                       reference=_solid_viscosity_ratio,
                       reference_label=r"solidified above ($\mu > 10^{{reference_exponent}} "
                                       r"\mu_0$)",
                       # up to beta = 10 the curves stay below 1e28 but where the film first
                       # solidifies (1e43 to 1e136 and beyond the float range): off scale
                       cap=1e30)),
                "Piezoviscous film ({viscosity_law} viscosity, {density_law} density) at {eps}",
                r"stick-or-rebound threshold against the piezoviscous number",
                figsize=(10.0, 7.6), grid=(2, 2)),
)}


def axis_figures(ds):
    """Yield ``(name, draw)`` of the figures of every further physics axis of the store that
    ``AXES`` declares (``Pi``: ``cavitation_eps=...`` and ``critical_stokes_vs_Pi``; ``beta``:
    ``piezoviscous_eps=...`` and ``critical_stokes_vs_beta``); none without one. Names carry the
    values of the store's other axes (``_suffix``). Each ``draw()`` returns a Figure; nothing is
    computed but St_c (``analysis``)."""
    import itertools

    dims = ds["status"].dims
    if "St" not in dims:
        return
    fixed = physics_from_json(dict(ds.attrs.get("fixed_physics", {})))
    if "eps" not in dims:
        ds = ds.expand_dims({"eps": [float(fixed["eps"])]})
    for spec in (s for a, s in AXES.items() if a in dims):
        others = [d for d in ds["status"].dims if d not in ("St", "eps", spec.axis)]
        for values in itertools.product(*(range(ds.sizes[a]) for a in others)):
            sel = dict(zip(others, values))
            cube = ds.isel(sel).transpose(spec.axis, "eps", "St")
            extra = {a: float(ds[a].values[i]) for a, i in sel.items()}
            for j, eps in enumerate(cube["eps"].values):
                yield (f"{spec.name}{_suffix({'eps': float(eps), **extra})}",
                       lambda c=cube.isel(eps=j), e=extra, s=spec: _axis_curves(s, c, e))
            yield (f"{spec.st_c_name}{_suffix(extra)}",
                   lambda c=cube, e=extra, s=spec: _axis_critical_stokes(s, c, e))


def _axis_curves(spec, cube, extra):
    """One eps: each of ``spec.panels`` against St, a curve per value of ``spec.axis``."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=spec.figsize, layout="constrained")
    axes = fig.subplots(*spec.grid).ravel()
    St, values = cube["St"].values, [float(v) for v in cube[spec.axis].values]
    ok = valid(cube)
    styles = spec.styles(values)
    for ax, panel in zip(axes, spec.panels):
        y = np.where(ok, np.asarray(cube[panel.variable].values, dtype=float), np.nan)
        for k, (v, (color, ls, lw)) in enumerate(zip(values, styles)):
            ax.plot(St, y[k], color=color, ls=ls, lw=lw, marker="o", ms=1.8, label=spec.label(v))
        ax.set_xscale("log")
        if panel.log:
            ax.set_yscale("log")
        ax.set_xlabel(r"Stokes number $St$")
        ax.set_ylabel(panel.label)
        ax.grid(True, which="major", lw=0.4, alpha=0.5)
        if panel.top is not None:
            ax.set_ylim(panel.bottom, panel.top)
        elif panel.bottom is not None:
            ax.set_ylim(bottom=panel.bottom)
        reference = panel.reference_value()
        if reference is not None:
            ax.axhline(reference, color="0.3", lw=0.8, ls=":")
        if panel.reference_label:
            label = panel.reference_label.replace(
                "{reference_exponent}", f"{math.log10(reference):g}") if reference > 0 else \
                panel.reference_label
            ax.text(0.01, reference, label, fontsize=7, color="0.3",
                    va="bottom", transform=ax.get_yaxis_transform())
        if panel.window is not None and np.isfinite(y).any():
            ax.set_ylim(max(float(np.nanmin(y)), panel.window[0]) - 0.5, panel.window[1])
        if panel.cap is not None:
            _cap(ax, y, panel.cap, St)
    failed = int(_failed(cube).sum())
    if failed:
        axes[0].text(0.01, 0.01, f"{failed} failed scene(s) left out", transform=axes[0].transAxes,
                     fontsize=7, color=FAILED_COLOR)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside right upper", frameon=False, fontsize=7)
    eps = float(cube["eps"].values)
    # the title names the physics as the solver resolves it where it is on ("auto" -> "barus")
    on = next((v for v in values if v != spec.classic), spec.classic)
    physics = Physics.from_mapping({**physics_from_json(dict(cube.attrs.get("fixed_physics", {}))),
                                    **extra, "St": float(St[0]), "eps": eps, spec.axis: on})
    fig.suptitle(spec.title.format_map({**physics.as_dict(), "eps": _eps_label(eps)}))
    _footer(fig, cube, {**extra, "eps": eps})
    return fig


def _cap(ax, y, cap, St):
    """Stop the y axis at ``cap`` if a value passes it, and say how far the curves go (inf: a
    value beyond the float range, left out of the curve)."""
    finite = np.isfinite(y)
    above = y[finite] > cap
    if not above.any() and not np.isinf(y).any():
        return
    lo = float(np.min(y[finite])) if finite.any() else cap
    # the margin matplotlib leaves, taken from the range shown rather than the full one
    ax.set_ylim(lo * (lo / cap) ** 0.05 if ax.get_yscale() == "log" else lo - 0.05 * (cap - lo),
                cap)
    notes = []
    if above.any():
        k = np.nanargmax(np.where(finite, y, np.nan))
        notes.append(f"off scale above: up to $10^{{{math.log10(y.flat[k]):.0f}}}$ at "
                     f"St = {float(St[k % St.size]):.3g}")
    n_inf = int(np.isinf(y).sum())
    if n_inf:
        at = ", ".join(f"{float(s):.3g}" for s in St[np.nonzero(np.isinf(y).any(axis=0))[0]])
        notes.append(f"beyond the float range ({n_inf} scene(s), St = {at}): left out")
    ax.text(0.99, 0.99, "\n".join(notes), transform=ax.transAxes, ha="right", va="top",
            fontsize=7, color="0.3")


def _axis_critical_stokes(spec, cube, extra):
    """St_c against ``spec.axis``, a curve per eps; the classic film's St_c dashed."""
    fig = _figure(_CURVES_SIZE)
    ax = fig.add_subplot()
    rows = [r for r in critical_stokes(cube) if math.isfinite(r["St_c"])]
    eps_values = [float(e) for e in cube["eps"].values]
    colors = eps_colors(eps_values)
    axis = spec.axis
    for i in range(len(eps_values) - 1, -1, -1):
        mine = [r for r in rows if r["eps"] == eps_values[i]]
        # on a log axis the classic film at inf has no place: it is the dashed line
        points = sorted((r[axis], r["St_c"]) for r in mine if math.isfinite(r[axis]))
        if points:
            x, y = zip(*points)
            ax.plot(x, y, color=colors[i], marker="o", ms=3.5, lw=1.3,
                    label=_eps_label(eps_values[i]))
        for r in mine:
            if r[axis] == spec.classic:
                ax.axhline(r["St_c"], color=colors[i], ls="--", lw=1.0)
    ax.plot([], [], color="0.3", ls="--", lw=1.0, label=spec.label(spec.classic))
    ax.axhline(EXPERIMENT_ST_C, color="k", ls=":", lw=1.0,
               label=r"experiments: no rebound below $St \approx 10$")
    shown = [float(v) for v in cube[axis].values if math.isfinite(v) and (v > 0 or not spec.log)]
    if not any(math.isfinite(r[axis]) for r in rows):  # no curve: the axis' values still shown
        ax.text(0.5, 0.5, "no St_c in this store off the classic film: at each of its values\n"
                f"of ${spec.symbol}$ every scene sticks, or every one rebounds (or is not done)",
                transform=ax.transAxes, ha="center", va="center", fontsize=8, color="0.3")
        if shown:
            ax.set_xlim(min(shown) / (2.0 if spec.log else 1.0) - (0.0 if spec.log else 1.0),
                        max(shown) * (2.0 if spec.log else 1.0) + (0.0 if spec.log else 1.0))
    if spec.log and shown:
        ax.set_xscale("log")
    ax.set_xlabel(spec.axis_label)
    ax.set_ylabel(r"critical Stokes number $St_c$")
    ax.set_ylim(bottom=0.0)
    ax.set_title(spec.st_c_title)
    ax.grid(True, which="major", lw=0.4, alpha=0.5)
    _legend_outside(ax)
    _footer(fig, cube, extra)
    return fig
