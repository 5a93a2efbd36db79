"""Old path of :mod:`contactpipe.pipeline.figures.regimes`: warns (DeprecationWarning) and is that
module."""
from .._util.moved import alias

alias(__name__, "contactpipe.pipeline.figures.regimes")
