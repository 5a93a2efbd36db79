"""Old path of :mod:`contactpipe.pipeline.cli.bench`: warns (DeprecationWarning) and is that
module."""
from .._util.moved import alias

alias(__name__, "contactpipe.pipeline.cli.bench")
