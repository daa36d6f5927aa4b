"""The whole trajectory of a scene: the gap against time, with its phases (``ehd scene --plot``).

Reads a finished ``solver.trajectory.Trajectory`` (SI) and, optionally, measured trajectories to
draw against it (benchmarks/bench_experiments.py); it never solves anything.
"""

from __future__ import annotations

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from . import TRAJECTORY_FIGURE
from .scene_plots import STYLE, save_figure

__all__ = ["plot_trajectory", "trajectory_axes"]

_COLOURS = {"approach": "C0", "near_field": "C3", "departure": "C2"}


def trajectory_axes(ax, tr, label="computed", t_shift=0.0):
    """Draw ``tr`` (gap in mm against time in ms from the first contact, ``t_shift`` added) on
    ``ax``, one colour per phase."""
    contact = tr.t[int(np.argmin(tr.gap))]
    names = sorted(tr.phases, key=tr.phases.get)
    edges = [tr.phases[n] for n in names] + [len(tr.t)]
    for k, name in enumerate(names):
        lo, hi = edges[k], min(edges[k + 1] + 1, len(tr.t))
        ax.plot((tr.t[lo:hi] - contact + t_shift) * 1e3, tr.gap[lo:hi] * 1e3,
                color=_COLOURS.get(name, "k"),
                label=f"{label}: {name.replace('_', ' ')}" if label else None)
    ax.axhline(tr.x0 * 1e3, color="0.5", lw=0.8, ls=":")
    ax.set_xlabel("time from the first contact $t$ [ms]")
    ax.set_ylabel("gap $x$ [mm]")


def plot_trajectory(tr, out_dir, reading=None, title=None):
    """Write ``trajectory.png`` and ``.pdf`` into ``out_dir``: the gap against time near the
    bounce (from 2 bounce heights above the wall), ``x0`` dotted, ``e_observed`` in the title."""
    with matplotlib.rc_context(STYLE):
        fig = Figure()
        ax = fig.add_subplot()
        trajectory_axes(ax, tr)
        top = max(tr.rebound_height, tr.x0)
        ax.set_ylim(0.0, 2.5 * top * 1e3)
        k = int(np.argmin(tr.gap))
        before = tr.t[:k][tr.gap[:k] > 2.5 * top]
        t0 = before[-1] if before.size else tr.t[0]
        ax.set_xlim((t0 - tr.t[k]) * 1e3, (tr.t[-1] - tr.t[k]) * 1e3 * 1.05 + 1e-6)
        text = title or "whole trajectory"
        if reading and reading.get("e_observed") is not None \
                and np.isfinite(reading["e_observed"]):
            text += f": e_observed = {reading['e_observed']:.3f}"
        ax.set_title(text)
        ax.legend(loc="upper right")
        return save_figure(fig, out_dir, TRAJECTORY_FIGURE)
