"""Old path of :mod:`contactpipe.planning.accuracy`: warns (DeprecationWarning), and is that
module."""
from ._util.moved import alias

alias(__name__, "contactpipe.planning.accuracy")
