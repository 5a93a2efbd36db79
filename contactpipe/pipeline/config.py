"""Old path of :mod:`contactpipe.pipeline.sweep.config`: warns (DeprecationWarning) and is that
module."""
from .._util.moved import alias

alias(__name__, "contactpipe.pipeline.sweep.config")
