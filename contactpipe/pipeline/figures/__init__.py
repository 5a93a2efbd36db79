"""The figures stage: the figures of an archive, a stress file or a sweep folder
(:mod:`.plot`), the panels of the stress figure (:mod:`.stress`), the rough-contact
figure (:mod:`.rough`), the fretting map
(:mod:`.fretting`) and its regime table (:mod:`.regimes`), all drawn into the figure of
:mod:`.canvas` when no axes are given."""
from .canvas import DPI, FIGSIZE, axes_of, new_figure

__all__ = ["new_figure", "axes_of", "FIGSIZE", "DPI"]
