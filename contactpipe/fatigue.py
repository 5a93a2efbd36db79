"""Old path of :mod:`contactpipe.post.fatigue`: warns (DeprecationWarning), and is that
module."""
from ._util.moved import alias

alias(__name__, "contactpipe.post.fatigue")
