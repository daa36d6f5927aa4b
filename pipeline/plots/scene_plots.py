"""Figures of one collision: profiles, motion, energies, dimple close-up.

Everything is plotted in the dimensionless variables of docs/model.md ("Scales"), with the scaling written on
each axis: axial lengths (gap ``h``, deformation ``w``, separation ``x``) over ``x1``, radius over
``sqrt(a x1)``, pressure over ``mu a v0 / x1^2``, force over ``6 pi mu a^2 v0 / x1``, velocity over
``v0``, energies over ``m v0^2 / 2``, time as ``tau = v0 t / x0``. A scene in physical units
(``ehd scene --plot``) adds the same quantities in SI units on the right and top axes
(``si_scales``). The figures read a finished ``solver.Collision``; they never solve anything.

Files are written as PNG and PDF with reproducible bytes (no timestamps or software versions in
the metadata, stack-notes.md). Figures are built as ``matplotlib.figure.Figure`` objects without
pyplot, so writing them needs no display and leaves the caller's backend alone.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from . import SCENE_FIGURES, figure_files
from ..writes import claim, retire

__all__ = ["plot_scene", "save_figure", "profile_rows", "plot_profiles", "plot_motion",
           "plot_energy", "plot_dimple", "radial_extent", "si_scales", "STYLE", "LABELS"]

# Fixed style: figures must not depend on a user's matplotlibrc, and the SVG hash salt fixes ids.
STYLE = {
    "figure.figsize": (6.4, 4.4), "figure.dpi": 100, "savefig.dpi": 150, "font.size": 10,
    "axes.grid": True, "grid.alpha": 0.3, "legend.fontsize": 8, "legend.framealpha": 0.85,
    "svg.hashsalt": "ehd-collision", "lines.linewidth": 1.4,
}
_PNG_META = {"Software": None}
_PDF_META = {"Creator": None, "Producer": None, "CreationDate": None}

LABELS = {
    "R": r"radius $r/\sqrt{a x_1}$",
    "H": r"gap $h/x_1$",
    "W": r"deformation $w/x_1$",
    "P": r"pressure $p\,/\,(\mu a v_0 / x_1^2)$",
    "tau": r"time $\tau = v_0 t / x_0$",
    "F": r"force $F\,/\,(6\pi\mu a^2 v_0/x_1)$",
    "V": r"velocity $v/v_0$",
    "X": r"separation $x/x_1$",
    "E": r"energy $/\,(m v_0^2/2)$",
}


# quantity -> (its name on an SI axis, SI unit)
_SI_NAMES = {"R": ("radius", "m"), "H": ("gap", "m"), "W": ("deformation", "m"),
             "P": ("pressure", "Pa"), "tau": ("time", "s"), "F": ("force", "N"),
             "V": ("velocity", "m/s"), "X": ("separation", "m"), "E": ("energy", "J")}
_SCALE_NAMES = {"R": r"$\sqrt{a x_1}$", "H": r"$x_1$", "W": r"$x_1$", "X": r"$x_1$",
                "P": r"$\mu a v_0/x_1^2$", "tau": r"$x_0/v_0$", "F": r"$6\pi\mu a^2 v_0/x_1$",
                "V": r"$v_0$", "E": r"$m v_0^2/2$"}
_PREFIXES = ((1e9, "G"), (1e6, "M"), (1e3, "k"), (1.0, ""), (1e-3, "m"), (1e-6, "µ"),
             (1e-9, "n"), (1e-12, "p"), (1e-15, "f"))


def si_scales(scene) -> dict:
    """The SI value of one unit of each plotted quantity of ``scene`` (a
    ``pipeline.scenes.scene.Scene``): ``{"H": x1 [m], "R": sqrt(a x1) [m], "P": mu a v0 / x1^2
    [Pa], "F": 6 pi mu a^2 v0 / x1 [N], "tau": x0 / v0 [s], "V": v0 [m/s], "E": m v0^2 / 2
    [J], ...}``."""
    x1 = scene.x1
    return {"R": float(np.sqrt(scene.reduced_radius * x1)), "H": x1, "W": x1, "X": x1,
            "P": scene.pressure_scale, "F": scene.force_scale, "tau": scene.time_scale,
            "V": scene.v0, "E": 0.5 * scene.reduced_mass * scene.v0 ** 2}


def _si_axis(ax, quantity: str, scales: dict | None, which: str = "y", span=None) -> None:
    """A right (``which="y"``) or top (``"x"``) axis with ``quantity`` in SI units, the prefix
    chosen for the values shown (``span``: their largest magnitude in the plot's units)."""
    if not scales or quantity not in scales:
        return
    scale = float(scales[quantity])
    if span is None:
        lo, hi = ax.get_ylim() if which == "y" else ax.get_xlim()
        span = max(abs(lo), abs(hi))
    big = abs(scale) * (span or 1.0)
    factor, prefix = next(((f, p) for f, p in _PREFIXES if big >= f), _PREFIXES[-1])
    k = scale / factor
    name, unit = _SI_NAMES[quantity]
    if (ax.get_yscale() if which == "y" else ax.get_xscale()) != "linear":
        # an SI twin of a symlog axis would get linear ticks: the unit goes into the label
        get, put = (ax.get_ylabel, ax.set_ylabel) if which == "y" else (ax.get_xlabel,
                                                                        ax.set_xlabel)
        put(f"{get()}  ({_SCALE_NAMES[quantity]} = {k:.4g} {prefix}{unit})")
        return
    functions = (lambda v: v * k, lambda v: v / k)
    sec = ax.secondary_yaxis("right", functions=functions) if which == "y" else \
        ax.secondary_xaxis("top", functions=functions)
    label = f"{name} [{prefix}{unit}]"
    (sec.set_ylabel if which == "y" else sec.set_xlabel)(label)


def save_figure(fig, out_dir, stem: str) -> list[Path]:
    """Write ``stem.png`` and ``stem.pdf`` into ``out_dir`` (created) with fixed metadata (the
    names ``pipeline.plots.figure_files`` gives, checked before the work)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / f"{stem}.png", out / f"{stem}.pdf"]
    for path, metadata in zip(paths, (_PNG_META, _PDF_META)):
        # a temporary, moved into place once the command completes (writes.guarded_dir)
        fig.savefig(claim(path), format=path.suffix[1:], metadata=metadata)
    return paths


def radial_extent(c) -> float:
    """Radius range worth showing: a few Hertz contact radii ``sqrt(delta_H)`` (at least the
    rigid film width ~2), capped by the grid."""
    from solver import hertz_overlap

    r = 2.2 * max(np.sqrt(hertz_overlap(c.St)), 2.0)
    return float(min(r, c.radius[-1])) if c.radius is not None else r


def _coupled_end(c) -> float:
    """End of the interesting part of the coupled phase: the rebound peak plus as long again as
    the approach took (the rest is slow relaxation); the whole phase without a rebound."""
    tau = c.profile_tau
    if c.v_r > 0 and np.isfinite(c.tau_max_rebound):
        return float(min(tau[-1], c.tau_max_rebound + (c.tau_max_rebound - tau[0])))
    return float(tau[-1])


def profile_rows(c, n: int = 8) -> np.ndarray:
    """Indices of ``n`` profile rows evenly spread in ``tau`` over the coupled phase (up to
    ``_coupled_end``), always including the time of ``v = 0`` when there is one."""
    tau = c.profile_tau
    targets = list(np.linspace(tau[0], _coupled_end(c), n))
    if np.isfinite(c.tau_v_zero):
        k = int(np.argmin(np.abs(np.array(targets) - c.tau_v_zero)))
        targets[k] = c.tau_v_zero
    rows = sorted({int(np.argmin(np.abs(tau - t))) for t in targets})
    return np.array(rows, dtype=int)


def _time_colors(n):
    return matplotlib.colormaps["viridis"](np.linspace(0.0, 0.9, max(n, 1)))


def plot_profiles(ax, c, quantity: str, rows=None, r_max=None, scales=None):
    """Profiles ``H``, ``W`` or ``P`` (``quantity``) against ``R`` at the given profile rows
    (``scales``: SI axes too, ``si_scales``)."""
    data = {"H": c.gap, "W": c.deformation, "P": c.pressure}[quantity]
    rows = profile_rows(c) if rows is None else rows
    r_max = radial_extent(c) if r_max is None else r_max
    keep = c.radius <= r_max * 1.0001
    for color, i in zip(_time_colors(len(rows)), rows):
        ax.plot(c.radius[keep], data[i, keep], color=color, label=rf"$\tau$ = {c.profile_tau[i]:.3g}")
    if quantity == "P":
        ax.axhline(0.0, color="0.5", lw=0.8)
    if quantity == "H":
        # the parabolic far field would set the scale; keep the contact region readable
        lo = min(float(data[i, keep].min()) for i in rows)
        top = 1.3 * max(float(data[i, 0]) for i in rows)
        ax.set_ylim(min(0.0, lo) - 0.03 * top, top)
    ax.set_xlim(0.0, r_max)
    ax.set_xlabel(LABELS["R"])
    ax.set_ylabel(LABELS[quantity])
    ax.legend(ncol=2)
    _si_axis(ax, quantity, scales)
    _si_axis(ax, "R", scales, which="x")
    return ax


def _series_window(c):
    """Mask of the time series worth plotting: the whole collision up to the end of the coupled
    phase plus 20% (the analytic rigid tail can run on for astronomically long)."""
    tau = np.asarray(c.series["tau"])
    phase = np.asarray(c.series["phase"])
    if np.any(phase == 1):
        t_end = tau[phase == 1][-1]
        return tau <= t_end + 0.2 * (t_end - tau[0])
    return np.ones_like(tau, dtype=bool)


def plot_motion(fig, c, scales=None):
    """Force, velocity and separation (with the minimum gap) against tau, three stacked panels
    (``scales``: SI axes too)."""
    s = c.series
    m = _series_window(c)
    tau = np.asarray(s["tau"])[m]
    axes = fig.subplots(3, 1, sharex=True)
    axes[0].plot(tau, np.asarray(s["F"])[m], color="C3")
    axes[0].set_ylabel(LABELS["F"])
    axes[1].plot(tau, np.asarray(s["V"])[m], color="C0")
    axes[1].axhline(0.0, color="0.5", lw=0.8)
    axes[1].set_ylabel(LABELS["V"])
    axes[2].plot(tau, np.asarray(s["X"])[m], color="C2", label=r"$x/x_1$ (undeformed surfaces)")
    axes[2].plot(tau, np.asarray(s["H_min"])[m], color="C1", ls="--",
                 label=r"$h_{\min}/x_1$ (film, smallest over $r$)")
    axes[2].axhline(0.0, color="0.5", lw=0.8)
    if np.max(np.asarray(s["X"])[m]) > 20.0:
        # small eps: the start (x0/x1 = eps^-0.4) would flatten the contact region to a line;
        # symlog keeps the approach and the (possibly negative) overlap both visible
        axes[2].set_yscale("symlog", linthresh=1.0)
    axes[2].set_ylabel(LABELS["X"])
    axes[2].set_xlabel(LABELS["tau"])
    axes[2].legend()
    for ax in axes:
        ax.label_outer()
        for t in (c.tau_v_zero, c.tau_max_rebound):  # v = 0, max rebound
            if np.isfinite(t):
                ax.axvline(t, color="0.6", lw=0.8, ls=":")
    for ax, q in zip(axes, ("F", "V", "X")):
        _si_axis(ax, q, scales)
    _si_axis(axes[0], "tau", scales, which="x")
    return axes


def plot_energy(ax, c, scales=None):
    """Kinetic and strain energy, work done by the fluid, and the dissipation (closure check)."""
    s = c.series
    m = _series_window(c)
    tau = np.asarray(s["tau"])[m]
    e_k, e_s = np.asarray(s["E_k"])[m], np.asarray(s["E_s"])[m]
    work = e_k + e_s - 1.0  # work done by the fluid on the spheres: change of E_k + E_s
    ax.plot(tau, e_k, color="C0", label=r"kinetic $E_k$")
    ax.plot(tau, e_s, color="C2", label=r"strain $E_s$")
    ax.plot(tau, work, color="C3", label=r"fluid work $W_f = E_k + E_s - 1$")
    ax.plot(tau, -np.asarray(s["dissipated"])[m], color="k", ls=":",
            label=r"$-$dissipated (equals $W_f$ if energy closes)")
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xlabel(LABELS["tau"])
    ax.set_ylabel(LABELS["E"])
    ax.legend(loc="center right")
    _si_axis(ax, "E", scales)
    _si_axis(ax, "tau", scales, which="x")
    return ax


def dimple_rows(c, n: int = 6) -> np.ndarray:
    """Profile rows while the central gap exceeds the off-axis minimum (the dimple), ``n`` of
    them spread over that interval, always including the deepest one."""
    from solver.collision import DIMPLE_DEPTH

    h = c.gap
    depth = h[:, 0] - h.min(axis=1)
    idx = np.nonzero(depth > DIMPLE_DEPTH)[0]
    if idx.size == 0:
        return idx
    picks = set(idx[np.linspace(0, idx.size - 1, min(n, idx.size)).round().astype(int)])
    picks.add(int(np.argmax(depth)))
    return np.array(sorted(picks), dtype=int)


def plot_dimple(ax, c, rows=None, scales=None):
    """Close-up of the gap near the axis while the dimple exists (``rows`` from ``dimple_rows``)."""
    rows = dimple_rows(c) if rows is None else rows
    h = c.gap
    i_deep = int(rows[np.argmax([h[i, 0] - h[i].min() for i in rows])])
    r_rim = float(c.radius[int(np.argmin(h[i_deep]))])
    r_max = 1.6 * r_rim
    keep = c.radius <= r_max
    lo = min(h[i, keep].min() for i in rows)
    hi = max(h[i, 0] for i in rows)
    for color, i in zip(_time_colors(len(rows)), rows):
        ax.plot(c.radius[keep], h[i, keep], color=color, marker=".", ms=3,
                label=rf"$\tau$ = {c.profile_tau[i]:.3g}")
    pad = 0.15 * (hi - lo)
    ax.set_ylim(lo - pad, hi + 2 * pad)
    ax.set_xlim(0.0, r_max)
    ax.set_xlabel(LABELS["R"])
    ax.set_ylabel(LABELS["H"])
    ax.legend(ncol=2)
    _si_axis(ax, "H", scales)
    _si_axis(ax, "R", scales, which="x")
    return ax


def _title(c, title=""):
    head = f"{title}\n" if title else ""
    return head + f"St = {c.St:.4g}, eps = {c.eps:.3g} ({c.model} model)"


def plot_scene(collision, out_dir, *, title: str = "", prefix: str = "",
               scales: dict | None = None) -> list[Path]:
    """Write the figures of one collision into ``out_dir``; return the files written.

    Parameters
    ----------
    collision : solver.Collision
        A finished collision (``save_profiles=True`` for the profile figures).
    out_dir : path-like
        Created if missing.
    title : str
        First title line (e.g. the scene's title); St, eps and the model are always shown.
    prefix : str
        Prepended to every file stem.
    scales : dict, optional
        ``si_scales(scene)`` of a scene in physical units: every axis also in SI units.

    Returns
    -------
    list of Path
        ``gap``, ``deformation``, ``pressure`` (EHD scenes with profiles), ``motion``,
        ``energy``, and ``dimple`` (only when a dimple forms), each as .png and .pdf.
    """
    c = collision
    written = []
    with matplotlib.rc_context(STYLE):
        has_profiles = c.model == "ehd" and c.pressure is not None and c.pressure.size > 0
        if has_profiles:
            for q, stem in (("H", "gap"), ("W", "deformation"), ("P", "pressure")):
                fig = Figure(layout="constrained")
                ax = fig.subplots()
                plot_profiles(ax, c, q, scales=scales)
                ax.set_title(_title(c, title), fontsize=9)
                written += save_figure(fig, out_dir, prefix + stem)
        fig = Figure(figsize=(6.4, 6.4), layout="constrained")
        plot_motion(fig, c, scales=scales)
        fig.suptitle(_title(c, title), fontsize=9)
        written += save_figure(fig, out_dir, prefix + "motion")
        fig = Figure(layout="constrained")
        ax = fig.subplots()
        plot_energy(ax, c, scales=scales)
        ax.set_title(_title(c, title), fontsize=9)
        written += save_figure(fig, out_dir, prefix + "energy")
        if has_profiles and c.dimple:
            fig = Figure(layout="constrained")
            ax = fig.subplots()
            plot_dimple(ax, c, scales=scales)
            ax.set_title(_title(c, title) + ": dimple close-up", fontsize=9)
            written += save_figure(fig, out_dir, prefix + "dimple")
    for stale in figure_files(prefix + stem for stem in SCENE_FIGURES):
        # a scene figure this scene has none of (a rigid scene's profiles, a dimple that did not
        # form): an earlier scene's, drawn into the same folder, goes as the new ones come
        if Path(out_dir, stale) not in written and Path(out_dir, stale).is_file():
            retire(Path(out_dir, stale))
    return written
