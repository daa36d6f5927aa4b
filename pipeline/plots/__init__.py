"""Figures: sweep maps (from a store), one collision in depth, the paper figures 2-11."""

# the figures ``scene_plots.plot_scene`` may write (``dimple`` only where a dimple forms); here,
# not there, so that a command checks its output folder without importing matplotlib
SCENE_FIGURES = ("gap", "deformation", "pressure", "motion", "energy", "dimple")
RESTITUTION_FIGURE = "restitution"  # restitution_plot's, a path's e against St
TRAJECTORY_FIGURE = "trajectory"  # trajectory_plot's, a released sphere's gap against time
FIGURE_SUFFIXES = (".png", ".pdf")  # each figure's files (``scene_plots.save_figure``)


def figure_files(stems) -> tuple:
    """The file names ``scene_plots.save_figure`` writes for ``stems``: checked before any work
    (``cli_shared.check_output_dir``), so that a folder in a figure's place is found then."""
    return tuple(stem + suffix for stem in stems for suffix in FIGURE_SUFFIXES)
