"""Old path of :mod:`contactpipe.scene.gridded`: warns (DeprecationWarning), and is that
module."""
from ._util.moved import alias

alias(__name__, "contactpipe.scene.gridded")
