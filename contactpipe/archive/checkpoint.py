"""The resume state of a resumable run, beside its target: checkpoint and lock.

A resumable run of ``DIR/NAME`` keeps three hidden files in ``DIR``:

* ``.NAME.resumable.part`` - the archive being written (:func:`resumable_part`);
* ``.NAME.ckpt.npz`` - the solver state after the last checkpointed instant
  (:class:`Checkpoint`): the scene's digest, the instant index ``k``, the instants
  ``written`` to the part file, and the state arrays the caller gives;
* ``.NAME.resume.lock`` - held while a run works on the other two
  (:func:`resume_lock`), so that two runs on one target never mix their files.

A checkpoint that cannot be read is reported as :class:`~contactpipe.exceptions.ArchiveError`
(the caller starts afresh); one of another scene is ignored. A checkpoint or part file that
is not a regular file (a FIFO, a device, a folder) is refused before it is opened
(:class:`~contactpipe.exceptions.OutputPathError`): reading a FIFO would block for ever.
The temporary files of a checkpoint being written when its process was killed
(``.NAME.ckpt.npz.<pid>-<token>.part``) are removed by the next run (:meth:`Checkpoint.clean`).
"""
from __future__ import annotations

import os
import pathlib
import stat
import zipfile

import numpy as np

from .._util.files import atomic_path, temporaries
from ..exceptions import ArchiveError, OutputPathError, one_line
from .schema import resumable_part

__all__ = ["Checkpoint", "resume_lock"]


def resume_lock(path) -> pathlib.Path:
    """The lock file of the resume state of ``path`` (``.NAME.resume.lock``)."""
    path = pathlib.Path(path)
    return path.with_name(f".{path.name}.resume.lock")


class Checkpoint:
    """The state of a resumable run after a completed instant (``.NAME.ckpt.npz``).

    Parameters
    ----------
    path : path-like
        The archive the run writes.
    digest : str
        The scene's digest: a checkpoint of another scene is not resumed.
    """

    def __init__(self, path, digest: str):
        self.path = pathlib.Path(path)
        self.file = self.path.with_name(f".{self.path.name}.ckpt.npz")
        self.part = resumable_part(self.path)
        self.digest = str(digest)

    def found(self) -> bool:
        """Whether a resume state (a checkpoint or a part file) is there."""
        return self._regular(self.file) or self._regular(self.part)

    @staticmethod
    def _regular(path: pathlib.Path) -> bool:
        """Whether ``path`` exists; OutputPathError when it is not a regular file."""
        try:
            st = os.stat(path)
        except FileNotFoundError:
            return False
        if not stat.S_ISREG(st.st_mode):
            raise OutputPathError(f"{path} is not a regular file (a FIFO, a device or a "
                                  f"folder): a resumable run keeps its state there; "
                                  f"remove it")
        return True

    def clean(self) -> list:
        """Remove the temporary files of checkpoints whose writing was killed (call only
        while holding :func:`resume_lock`); returns their names."""
        removed = []
        for p in temporaries(self.file):
            p.unlink(missing_ok=True)
            removed.append(p.name)
        return removed

    def load(self) -> dict | None:
        """The saved arrays (with ``k`` and ``written``), or None when there is nothing to
        resume (no checkpoint, no part file, or another scene's).

        Raises
        ------
        ArchiveError
            The checkpoint exists but cannot be read (truncated, not an npz, keys missing).
        OutputPathError
            The checkpoint or the part file is not a regular file (a FIFO, a device, a
            folder); nothing is opened.
        """
        have_file, have_part = self._regular(self.file), self._regular(self.part)
        if not (have_file and have_part):
            return None
        try:
            with np.load(self.file, allow_pickle=False) as z:
                state = {k: z[k] for k in z.files}
            digest = str(state.pop("digest"))
            int(state["k"]), int(state["written"])
        except (OSError, ValueError, KeyError, EOFError, TypeError,
                zipfile.BadZipFile) as e:
            raise ArchiveError(f"{self.file}: unreadable checkpoint ({one_line(e)})") from None
        if digest != self.digest:
            return None                  # another scene: start afresh
        return state

    def save(self, k: int, written: int, arrays: dict) -> None:
        """Record the state after instant ``k`` with ``written`` instants in the part file
        (atomic: a reader sees the previous checkpoint or this one)."""
        full = {"digest": np.array(self.digest), "k": np.array(k),
                "written": np.array(written), **arrays}
        with atomic_path(self.file) as tmp, open(tmp, "wb") as f:
            np.savez(f, **full)

    def remove(self) -> None:
        """Drop the checkpoint (the run finished, failed, or its state was damaged)."""
        self.file.unlink(missing_ok=True)

    def discard(self) -> None:
        """Drop the checkpoint and the part file: the next run starts afresh."""
        self.remove()
        self.part.unlink(missing_ok=True)
