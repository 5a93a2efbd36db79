"""Old path of :mod:`contactpipe.pipeline.cli.compare`: warns (DeprecationWarning) and is that
module."""
from .._util.moved import alias

alias(__name__, "contactpipe.pipeline.cli.compare")
