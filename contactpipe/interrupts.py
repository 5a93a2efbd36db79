"""Old path of :mod:`contactpipe._util.interrupts`: warns (DeprecationWarning), and is that
module."""
from ._util.moved import alias

alias(__name__, "contactpipe._util.interrupts")
