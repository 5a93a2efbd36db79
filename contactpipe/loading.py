"""Old path of :mod:`contactpipe.scene.loading`: warns (DeprecationWarning), and is that
module."""
from ._util.moved import alias

alias(__name__, "contactpipe.scene.loading")
