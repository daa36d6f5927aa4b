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

from . import RESTITUTION_FIGURE

__all__ = ["plot_restitution"]


# the e a curve shows -> (its label, colour)
CURVES = {"e_far": ("dry DEM: $e_{far}$", "C0"), "e_wet": ("resolved CFD-DEM: $e_{wet}$", "C1")}
_RANGE_KEY = {"e_far": "e_for_dem_range", "e_wet": "e_for_cfd_dem_range"}


def _curve(ax, ok, st, key, thresholds=()):
    """One e along the path, its sticking points open, its range a band where computed. No line
    joins a sticking scene to a rebounding one: drawn straight, it showed e > 0 below the
    threshold (e_far 0.07 at St 10 with St_c 11.04). The line through the rebounding scenes
    starts at e = 0 at the bisected ``St_c`` where the path has one, and the line along 0 of the
    sticking scenes ends there; without one, the two lines leave the bracket open."""
    label, colour = CURVES[key]
    e = np.array([float(getattr(r.collision, key)) for r in ok])
    if not np.isfinite(e).any():
        return
    stuck = e == 0.0
    st_c = [t.St_c for t in thresholds if t.key == key and t.St_c is not None]
    zero_st, rise_st, rise_e = st[stuck], st[~stuck], e[~stuck]
    if st_c:
        zero_st = np.sort(np.append(zero_st[zero_st < st_c[0]], st_c[0]))
        up = rise_st > st_c[0]
        rise_st, rise_e = np.append(st_c[0], rise_st[up]), np.append(0.0, rise_e[up])
    order = np.argsort(rise_st)  # a path may run down in St (--from above --to)
    ax.plot(np.sort(zero_st), np.zeros(zero_st.size), color=colour, lw=1.4)
    ax.plot(rise_st[order], rise_e[order], color=colour, lw=1.4, label=label)
    ax.plot(st[~stuck], e[~stuck], ls="none", marker="o", ms=4, color=colour)
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


def _minor_labels(axis):
    """A formatter of ``axis``'s (log) minor ticks: at 2 and 5 times a power of ten only where
    the axis spans more than half a decade (matplotlib labelled 3, 4 and 6 too on a path of
    about a decade, and ``3x10^0`` ran into ``4x10^0``), every one on a shorter axis."""
    def label(x, _pos=None) -> str:
        if not x > 0.0:
            return ""
        power = int(np.floor(np.log10(x) + 1e-9))
        mantissa = x / 10.0 ** power
        lo, hi = sorted(axis.get_view_interval())
        wide = lo > 0.0 and np.log10(hi / lo) > 0.5
        if wide and min(abs(mantissa - 2.0), abs(mantissa - 5.0)) > 1e-6:
            return ""
        return rf"${mantissa:.3g}\times10^{{{power}}}$"
    return label


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
            _curve(ax, ok, st, key, thresholds)
        rough = [r.scene.stokes for r in ok if any(w.check == "roughness" for w in r.warnings)]
        if rough:
            ax.plot(rough, np.full(len(rough), 1.02), ls="none", marker="v", color="C3", ms=4,
                    transform=ax.get_xaxis_transform(), clip_on=False,
                    label="roughness decides (validity warning)")
        _threshold(ax, ok, st, thresholds)
        ax.set_xscale("log")
        ax.xaxis.set_minor_formatter(_minor_labels(ax.xaxis))
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
            sec.xaxis.set_minor_formatter(_minor_labels(sec.xaxis))
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.18), ncol=2, frameon=False)
        ax.set_title(title, fontsize=9)
        return save_figure(fig, out_dir, RESTITUTION_FIGURE)
