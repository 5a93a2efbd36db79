"""The figure every plotting function of the pipeline draws into when given no axes.

:func:`new_figure`: an 8 x 5 in :class:`matplotlib.figure.Figure` at 100 dpi with a tight
layout, never attached to pyplot (no global state, no window). Shared by
:mod:`contactpipe.pipeline.figures.plot` (which re-exports it) and the figure modules below it
(:mod:`contactpipe.pipeline.figures.fretting`).
"""
from __future__ import annotations

__all__ = ["new_figure", "axes_of", "FIGSIZE", "DPI"]

FIGSIZE = (8.0, 5.0)        # in
DPI = 100


def new_figure():
    """A new 8 x 5 in Figure at 100 dpi with a tight layout (not attached to pyplot)."""
    # matplotlib is imported here, not at the top: a heavy import that only drawing needs
    # (the command line and the pipeline import these modules whatever they run)
    from matplotlib.figure import Figure
    return Figure(figsize=FIGSIZE, dpi=DPI, layout="tight")


def axes_of(ax):
    """(Figure, Axes): ``ax`` and its figure, or a new figure with one Axes."""
    if ax is not None:
        return ax.get_figure(), ax
    fig = new_figure()
    return fig, fig.add_subplot()
