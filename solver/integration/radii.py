"""The radial grid's nodes in reference units (the inner region on ``[0, 1]``): numpy only, so
that the numerical settings are checked against the grid they make (solver/settings.py) without
compiling or importing the solver's compiled code; integration/grid.py builds the grid on them.
"""

import numpy as np

# the most nodes a grid may have: its elastic matrix holds N^2 doubles (800 MB here), which a
# scene builds once; a grid of outer_extent 1e4 at stretch 1 asked for 6.9 TiB (a hostile review)
MAX_NODES = 10_000


def reference_radii(n_inner: int, axis_ratio: float, axis_extent: float, stretch: float,
                    outer_extent: float, max_rel: float) -> np.ndarray:
    """Nodes in reference units (inner region [0, 1]).

    - Inner region: cells of size ``1/n_inner``, refined towards the axis inside
      ``R < axis_extent``, where the size grows linearly from ``axis_ratio / n_inner`` at the
      axis: during rebound the tension pinches the film at the axis into a narrow cone whose
      tip sets the minimum gap. A refined zone that reaches within half a cell of 1 ends at 1
      (``axis_extent`` near 1 had stepped past it, and the inner region's last cell came out
      negative: the outer loop then never ended).
    - Outer region: cell sizes growing by ``stretch``, capped at ``max_rel * R``, up to
      ``outer_extent``.

    Raises ValueError, naming the settings, where the grid would have more than ``MAX_NODES``
    nodes (found before they are all built).
    """
    h_edge = 1.0 / n_inner
    nodes = [0.0]
    if axis_ratio < 1.0 and axis_extent > 0.0:
        while nodes[-1] < axis_extent:
            r = nodes[-1]
            step = h_edge * (axis_ratio + (1.0 - axis_ratio) * r / axis_extent)
            if r + 1.5 * step >= 1.0:
                nodes.append(1.0)
                break
            nodes.append(r + step)
    if nodes[-1] < 1.0:
        m = max(1, int(np.ceil((1.0 - nodes[-1]) / h_edge - 0.5)))
        nodes.extend(np.linspace(nodes[-1], 1.0, m + 1)[1:])
    h = nodes[-1] - nodes[-2]
    while nodes[-1] < outer_extent:
        h = min(h * stretch, max_rel * nodes[-1])
        nodes.append(nodes[-1] + h)
        if len(nodes) > MAX_NODES:
            raise ValueError(
                f"the grid of these settings (n_inner {n_inner}, axis_ratio {axis_ratio:g}, "
                f"stretch {stretch:g}, outer_extent {outer_extent:g}, max_rel {max_rel:g}) "
                f"would have more than {MAX_NODES} nodes (its elastic matrix alone 0.8 GB and "
                "more): raise stretch, or lower outer_extent or n_inner")
    return np.array(nodes)
