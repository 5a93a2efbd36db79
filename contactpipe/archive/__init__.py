"""Archives: one simulation per netCDF4 file, written atomically, checksummed, verified.

Writing (:mod:`~contactpipe.archive.writer`)
    :class:`ArchiveWriter` streams instants into a hidden temporary file beside the target
    and publishes it by an atomic rename only after reading it back whole and finding
    nothing wrong; :class:`MemoryWriter` has the same interface and returns a Dataset;
    :func:`save` writes a whole Dataset the same way after :func:`validate`. Every
    variable carries fletcher32 checksums.
Reading (:mod:`~contactpipe.archive.reader`)
    :func:`open_archive` opens lazily and refuses a missing, unreadable, interrupted or
    off-schema file; ``verify=True`` reads every value once (:func:`content_problems`).
    :func:`is_complete` is the cheap yes/no of sweeps.
Resuming (:mod:`~contactpipe.archive.checkpoint`)
    the part file (:func:`resumable_part`), the :class:`Checkpoint` and the lock
    (:func:`resume_lock`) of a resumable run.

The schema itself (dimensions, variables, units, attributes) is documented in
docs/archive.md and tabulated in :mod:`contactpipe.nomenclature`.
"""
from .checkpoint import Checkpoint, resume_lock
from .content import COULOMB_RTOL, content_problems
from .reader import is_complete, open_archive
from .schema import PRECISIONS, SERIES_CHUNK, resumable_part, schema_problems
from .writer import ArchiveWriter, MemoryWriter, save, to_dataset, validate

__all__ = ["ArchiveWriter", "MemoryWriter", "to_dataset", "save", "open_archive",
           "is_complete", "validate", "resumable_part", "content_problems",
           "schema_problems", "Checkpoint", "resume_lock", "PRECISIONS", "SERIES_CHUNK",
           "COULOMB_RTOL"]
