"""The package version, from the installed metadata (nothing internal imported)."""
from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _metadata_version

try:
    __version__ = _metadata_version("contactpipe")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0.1.0"
