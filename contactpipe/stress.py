"""Old path of :mod:`contactpipe.post.stress`: warns (DeprecationWarning), and is that
module."""
from ._util.moved import alias

alias(__name__, "contactpipe.post.stress")
