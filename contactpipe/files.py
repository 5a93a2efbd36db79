"""Old path of :mod:`contactpipe._util.files`: warns (DeprecationWarning), and is that
module."""
from ._util.moved import alias

alias(__name__, "contactpipe._util.files")
