"""Old path of :mod:`contactpipe.pipeline.compare.reference`: warns (DeprecationWarning) and is that
module."""
from .._util.moved import alias

alias(__name__, "contactpipe.pipeline.compare.reference")
