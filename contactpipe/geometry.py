"""Old path of :mod:`contactpipe.scene.geometry`: warns (DeprecationWarning), and is that
module."""
from ._util.moved import alias

alias(__name__, "contactpipe.scene.geometry")
