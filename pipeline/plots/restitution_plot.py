"""``ehd restitution SCENE --plot DIR``: the wet restitution e of a scene along its path in
impact speed or size, against the Stokes number (bottom axis) and the path's quantity in SI units
(top axis: v0 or the radius of body1), with the sticking threshold marked: the bisected ``St_c``
(``--threshold``, ``pipeline.scenes.threshold``) or else the interval between the last sticking
and the first rebounding scene of the path. Written as ``restitution.png`` and ``.pdf`` with
reproducible bytes (``scene_plots.save_figure``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["plot_restitution"]


def plot_restitution(results, vary: str, out_dir, *, threshold=None, title: str = "") -> list:
    """Write the figure of ``results`` (``SceneResult`` along the path, in order) into
    ``out_dir``; returns the paths."""
    import matplotlib
    from matplotlib.figure import Figure

    from .scene_plots import STYLE, save_figure

    ok = [r for r in results if r.collision.ok]
    st = np.array([r.scene.stokes for r in ok])
    e = np.array([r.collision.e_wet for r in ok])
    if vary == "v0":
        q = np.array([r.scene.v0 for r in ok])
        q_label, unit, factor = "impact speed $v_0$", "m/s", 1.0
    else:
        q = np.array([r.scene.body1.radius for r in ok])
        q_label, unit, factor = "radius of body 1", "µm", 1e6
    with matplotlib.rc_context(STYLE):
        fig = Figure(layout="constrained")
        ax = fig.subplots()
        stuck = e == 0.0
        ax.plot(st, e, color="C0", lw=1.4, marker="o", ms=4, label=r"$e_{wet}$ (rebounds)")
        ax.plot(st[stuck], e[stuck], ls="none", marker="o", ms=5, mfc="white", color="C0",
                label="sticks ($e_{wet} = 0$)")
        rough = [r.scene.stokes for r in ok if any(w.check == "roughness" for w in r.warnings)]
        if rough:
            ax.plot(rough, np.full(len(rough), 1.02), ls="none", marker="v", color="C3", ms=4,
                    transform=ax.get_xaxis_transform(), clip_on=False,
                    label="roughness decides (validity warning)")
        if threshold is not None and threshold.St_c is not None:
            ax.axvline(threshold.St_c, color="k", ls="--", lw=1.0,
                       label=rf"sticking threshold $St_c$ = {threshold.St_c:.4g}")
        elif stuck.any() and (~stuck).any():
            i = int(np.argmax(~stuck & np.concatenate([[False], stuck[:-1]])))
            if i > 0:
                ax.axvspan(st[i - 1], st[i], color="0.88", lw=0,
                           label=f"threshold between St = {st[i - 1]:.3g} and {st[i]:.3g}")
        ax.set_xscale("log")
        ax.set_ylim(0.0, 1.0)
        ax.set_xlabel(r"Stokes number $St = m v_0 / (6 \pi \mu a^2)$")
        ax.set_ylabel(r"wet restitution $e_{wet}$ (at $x_0$)")
        ax.grid(True, which="major", lw=0.4, alpha=0.5)
        if st.size:
            # St is proportional to v0 and to the size along the path: one linear map
            k = float(np.median(q / st)) * factor
            sec = ax.secondary_xaxis("top", functions=(lambda s: s * k, lambda v: v / k))
            sec.set_xlabel(f"{q_label} [{unit}]")
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.18), ncol=2, frameon=False)
        ax.set_title(title, fontsize=9)
        return save_figure(fig, out_dir, "restitution")
