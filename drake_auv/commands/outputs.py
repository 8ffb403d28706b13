"""Output locations checked before any work.

`drake-auv run`, `plan`, `reconstruct`, `replay`, `simulate` and `lawnmower` call
`output_folder` / `output_file` before their work, so a file in the way, a folder that cannot
be created or written, or a disk without room ends the command with one line (a ValueError
naming the option and the path) before a dive is flown, a plan computed or a surface built. The check writes and removes one
empty probe file, so it sees what the process can really do (read-only mounts, permissions,
root included); nothing already in the folder is touched.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

MiB = 2 ** 20


def output_folder(path, option: str, need_bytes: int) -> Path:
    """Creates folder `path` (with its parents) when missing and checks that a file can be
    created in it and that its file system has `need_bytes` free; returns the path."""
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise ValueError(f"{option} {folder}: a file is in the way (an output folder is needed; "
                         "nothing was written)")
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder, prefix=".drake-auv-probe-"):
            pass
    except OSError as err:
        raise ValueError(f"{option} {folder}: cannot write there "
                         f"({err.strerror or err}{_where(err, folder)})") from None
    free = shutil.disk_usage(folder).free
    if free < need_bytes:
        raise ValueError(f"{option} {folder}: {free / MiB:.1f} MiB free on its disk, the outputs "
                         f"need at least {need_bytes / MiB:.0f} MiB")
    return folder


def output_file(path, option: str, suffixes: tuple[str, ...], need_bytes: int) -> Path:
    """Checks that file `path` can be written: one of `suffixes` (lower case, with the dot),
    not a folder nor a special file, and its folder (created when missing) writable with
    `need_bytes` free; returns the path. An existing file is left as it is."""
    file = Path(path)
    if file.is_dir():
        raise ValueError(f"{option} {file} is a folder; give a file name")
    if file.suffix.lower() not in suffixes:
        raise ValueError(f"{option} {file}: unknown extension {file.suffix!r} "
                         f"(use {', '.join(suffixes)})")
    if file.exists() and not file.is_file():
        raise ValueError(f"{option} {file} exists and is not a regular file")
    output_folder(file.parent, option, need_bytes)
    return file


def _where(err: OSError, folder: Path) -> str:
    """': PATH' when the OSError is about another path than `folder` (a parent in the way)."""
    name = err.filename
    return f": {name}" if name is not None and Path(name) != folder else ""
