"""Old path of :mod:`contactpipe.pipeline.figures.plot`: warns (DeprecationWarning) and is that
module."""
from .._util.moved import alias

alias(__name__, "contactpipe.pipeline.figures.plot")
