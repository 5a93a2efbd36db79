"""Old path of :mod:`contactpipe.scene.parts`: warns (DeprecationWarning), and is that
module."""
from ._util.moved import alias

alias(__name__, "contactpipe.scene.parts")
