"""Output files: checked before a run, written atomically (a temporary file in the target
folder, then a rename).

A run killed at any moment leaves either the previous complete file or the new
complete file, never a half-written one (``os.replace`` is atomic on POSIX when the
temporary file lives on the same file system as the target).
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any


@contextlib.contextmanager
def atomic_open(path: str | os.PathLike[str], mode: str = "w") -> Iterator[IO[Any]]:
    """Open a temporary file beside ``path``; rename it onto ``path`` on success.

    On an exception the temporary file is removed and ``path`` is left untouched.
    ``mode`` is ``"w"`` (text) or ``"wb"`` (binary).
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"mode must be 'w' or 'wb', got {mode!r}")
    target = Path(path)
    folder = target.parent if str(target.parent) else Path(".")
    if not folder.is_dir():
        raise FileNotFoundError(f"output folder does not exist: {folder}")
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=folder)
    # mkstemp creates 0600 files; give the result the usual permissions of the umask.
    umask = os.umask(0)
    os.umask(umask)
    os.fchmod(fd, 0o666 & ~umask)
    try:
        with os.fdopen(fd, mode) as handle:
            yield handle
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def write_text_atomic(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` to ``path`` atomically."""
    with atomic_open(path, "w") as handle:
        handle.write(text)


def write_json_atomic(path: str | os.PathLike[str], obj: Any, indent: int = 2) -> None:
    """Write ``obj`` as JSON to ``path`` atomically (NaN is refused, not written)."""
    text = json.dumps(obj, indent=indent, allow_nan=False)
    write_text_atomic(path, text + "\n")


def writable_file(path: str | None) -> Path | None:
    """Check before the run that an output file's folder exists (fail early, not after minutes)."""
    if path is None:
        return None
    p = Path(path)
    if not p.parent.exists() and str(p.parent) not in ("", "."):
        raise ValueError(f"output folder does not exist: {p.parent}")
    if p.is_dir():
        raise ValueError(f"output path is a folder, not a file: {p}")
    return p
