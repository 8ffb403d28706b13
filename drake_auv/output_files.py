"""The one way every command writes an output file: into a private temporary folder beside it,
then renamed into place (pure Python).

`replacing(path)` yields a temporary path (the same file name, in a new folder `mkdtemp` makes
in `path`'s folder, readable by its owner only); when the block ends without an error the file
is renamed onto `path` with `os.replace`, which never follows a link at `path`: a symbolic link
there is replaced by the new regular file and whatever it pointed to is left as it was. No one
else can plant a link inside the private folder, so writers that take a file name (matplotlib,
trimesh, rasterio, laspy) cannot be redirected either. A reader sees the old file or the new
one, never a part; after an error the temporary folder is removed and `path` is untouched. A
folder at `path` is refused (`IsADirectoryError`, one line naming it). A process killed while
writing leaves a hidden `.NAME.partial-*` folder beside `path`.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from pathlib import Path

PARTIAL = ".partial-"  # the temporary folders' names: `.NAME.partial-XXXXXXXX`


@contextlib.contextmanager
def replacing(path, sync: bool = False):
    """Yields a temporary `Path` to write `path`'s content to; renames it onto `path` when the
    block ends without an error (`sync`: flushed to the disk first, the folder too)."""
    target = Path(path)
    work = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name}{PARTIAL}"))
    try:
        temporary = work / target.name
        yield temporary
        if not temporary.is_file() or temporary.is_symlink():
            raise FileNotFoundError(f"{target}: nothing was written")
        if target.is_dir() and not target.is_symlink():
            raise IsADirectoryError(f"{target} is a folder; an output file cannot replace it")
        if sync:
            _fsync(temporary, os.O_RDONLY)
        os.replace(temporary, target)
        if sync:
            _fsync(target.parent, os.O_RDONLY)
    finally:
        shutil.rmtree(work, ignore_errors=True)


@contextlib.contextmanager
def open_replacing(path, mode: str = "w", sync: bool = False, **kwargs):
    """`open(path, mode, **kwargs)` ("w" or "wb") through `replacing`: yields the file."""
    if mode not in ("w", "wb"):
        raise ValueError(f"open_replacing: mode must be 'w' or 'wb', got {mode!r}")
    with replacing(path, sync) as temporary, open(temporary, mode.replace("w", "x"),
                                                  **kwargs) as f:
        yield f


def write_text(path, text: str, sync: bool = False) -> None:
    """Writes `text` (UTF-8) to `path` through `replacing`."""
    with open_replacing(path, "w", sync, encoding="utf-8") as f:
        f.write(text)


def _fsync(path: Path, flags: int) -> None:
    fd = os.open(path, flags)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
