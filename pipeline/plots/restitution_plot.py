"""``ehd restitution SCENE --plot DIR``: the restitution of a scene along its path in speed or
size, in the e of each kind of code (dry DEM ``e_far``, resolved CFD-DEM ``e_wet``; each with its
range as a band with ``--range``), against the Stokes number (bottom axis) and the path's
quantity in SI units (top axis: v0, the approach speed or the radius of body1), with the sticking
thresholds marked: the bisected ``St_c`` (``--threshold``, ``pipeline.scenes.threshold``) or
else the interval between the last sticking and the first rebounding scene of the path. Written as ``restitution.png`` and ``.pdf`` with
reproducible bytes (``scene_plots.save_figure``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["plot_restitution"]


# the e a curve shows -> (its label, colour)
CURVES = {"e_far": ("dry DEM: $e_{far}$", "C0"), "e_wet": ("resolved CFD-DEM: $e_{wet}$", "C1")}
_RANGE_KEY = {"e_far": "e_for_dem_range", "e_wet": "e_for_cfd_dem_range"}


def _curve(ax, ok, st, key):
    """One e along the path, its sticking points open, its range a band where computed."""
    label, colour = CURVES[key]
    e = np.array([float(getattr(r.collision, key)) for r in ok])
    if not np.isfinite(e).any():
        return
    stuck = e == 0.0
    ax.plot(st, e, color=colour, lw=1.4, marker="o", ms=4, label=label)
    ax.plot(st[stuck], e[stuck], ls="none", marker="o", ms=5, mfc="white", color=colour)
    spans = [r.answer.get(_RANGE_KEY[key]) for r in ok]
    if all(spans):
        lo, hi = np.array(spans).T
        ax.fill_between(st, lo, hi, color=colour, alpha=0.18, lw=0,
                        label=f"range of {label.split(':')[0]} (unknowns)")


def _threshold(ax, ok, st, thresholds):
    """The bisected thresholds, or else the interval between the last sticking and the first
    rebounding scene in e_wet."""
    styles = {"e_far": ("C0", "--"), "e_wet": ("C1", ":")}
    for t in thresholds:
        if t.St_c is not None:
            colour, ls = styles[t.key]
            name = t.key.replace("_", "_{") + "}"
            ax.axvline(t.St_c, color=colour, ls=ls, lw=1.0,
                       label=rf"threshold in ${name}$: $St_c$ = {t.St_c:.4g}")
    if thresholds:
        return
    stuck = np.array([r.collision.e_wet == 0.0 for r in ok])
    if stuck.any() and (~stuck).any():
        i = int(np.argmax(~stuck & np.concatenate([[False], stuck[:-1]])))
        if i > 0:
            ax.axvspan(st[i - 1], st[i], color="0.88", lw=0,
                       label=f"$e_{{wet}}$ threshold between St = {st[i - 1]:.3g} and {st[i]:.3g}")


def _loglog(x, lx, ly):
    """``y(x)`` piecewise linear in log-log through the points ``(lx, ly)`` (increasing ``lx``),
    extended by the end pieces' slopes."""
    u = np.log(np.maximum(np.asarray(x, dtype=float), 1e-300))
    inside = np.interp(u, lx, ly)
    lo = ly[0] + (u - lx[0]) * (ly[1] - ly[0]) / (lx[1] - lx[0])
    hi = ly[-1] + (u - lx[-1]) * (ly[-1] - ly[-2]) / (lx[-1] - lx[-2])
    return np.exp(np.where(u < lx[0], lo, np.where(u > lx[-1], hi, inside)))


def plot_restitution(results, vary: str, out_dir, *, thresholds=(), title: str = "") -> list:
    """Write the figure of ``results`` (``SceneResult`` along the path, in order) into
    ``out_dir``: ``e_far`` (dry DEM) and ``e_wet`` (resolved CFD-DEM) against St, each with its
    range as a band where the results carry one (``ehd restitution --range``), the thresholds
    (``threshold.Threshold``) marked; the top axis is the path's quantity (v0, the approach
    speed or body1's radius). Returns the paths."""
    import matplotlib
    from matplotlib.figure import Figure

    from pipeline.dem.export import PATHS, path_value

    from .scene_plots import STYLE, save_figure

    ok = [r for r in results if r.collision.ok]
    st = np.array([r.scene.stokes for r in ok])
    q_label, unit = PATHS[vary]
    factor = 1e6 if vary == "radius" else 1.0
    unit = "µm" if vary == "radius" else unit
    q = np.array([path_value(r.scene, vary) for r in ok]) * factor
    with matplotlib.rc_context(STYLE):
        fig = Figure(layout="constrained")
        ax = fig.subplots()
        for key in CURVES:
            _curve(ax, ok, st, key)
        rough = [r.scene.stokes for r in ok if any(w.check == "roughness" for w in r.warnings)]
        if rough:
            ax.plot(rough, np.full(len(rough), 1.02), ls="none", marker="v", color="C3", ms=4,
                    transform=ax.get_xaxis_transform(), clip_on=False,
                    label="roughness decides (validity warning)")
        _threshold(ax, ok, st, thresholds)
        ax.set_xscale("log")
        ax.set_ylim(0.0, 1.0)
        ax.set_xlabel(r"Stokes number $St = m v_0 / (6 \pi \mu a^2)$ (at $x_0$)")
        ax.set_ylabel("restitution $e$ (open: sticks, $e = 0$)")
        ax.grid(True, which="major", lw=0.4, alpha=0.5)
        if st.size > 1:
            # the path's quantity against St: proportional for v0 and size, affine for the
            # approach speed; interpolated in log-log between the scenes
            order = np.argsort(st)
            ls, lq = np.log(st[order]), np.log(q[order])
            sec = ax.secondary_xaxis("top", functions=(lambda s: _loglog(s, ls, lq),
                                                       lambda v: _loglog(v, lq, ls)))
            sec.set_xlabel(f"{q_label} [{unit}]")
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.18), ncol=2, frameon=False)
        ax.set_title(title, fontsize=9)
        return save_figure(fig, out_dir, "restitution")
