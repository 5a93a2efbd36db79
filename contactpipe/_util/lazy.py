"""Names of a package that load their module on first use (PEP 562 module ``__getattr__``),
so that importing the package stays light."""
from __future__ import annotations

import importlib

__all__ = ["lazy_names"]


def lazy_names(package: str, table: dict, namespace: dict):
    """The ``__getattr__`` and ``__dir__`` of ``package`` whose public names ``table`` maps
    to the submodules that define them; a loaded name is kept in ``namespace`` (the
    package's globals), so it loads once."""

    def __getattr__(name):
        module = table.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{module}"), name)
        namespace[name] = value
        return value

    def __dir__():
        return sorted(set(namespace) | set(table))

    return __getattr__, __dir__
