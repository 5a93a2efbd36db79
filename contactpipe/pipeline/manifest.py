"""Old path of :mod:`contactpipe.pipeline.sweep.manifest`: warns (DeprecationWarning) and is that
module."""
from .._util.moved import alias

alias(__name__, "contactpipe.pipeline.sweep.manifest")
