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

`write_json` writes strict JSON (RFC 8259: no NaN, no Infinity): a number that is not finite
becomes null, and beside its key `KEY_null_reason` says what it was ("NaN", "+Infinity",
"-Infinity"; for a list, how many of its entries and which).
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np

PARTIAL = ".partial-"  # the temporary folders' names: `.NAME.partial-XXXXXXXX`


@contextlib.contextmanager
def replacing(path, sync: bool = False):
    """Yields a temporary `PlannedPath` to write `path`'s content to; renames it onto `path` when the
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


def json_ready(value):
    """`value` (mappings, lists, tuples, numbers, numpy scalars and arrays, ...) with every
    number that is not finite replaced by None, and the reason beside it (see the module)."""
    return _finite(value)[0]


def write_json(path, value, indent: int | None = 2, sync: bool = False, **dumps) -> None:
    """Writes `json_ready(value)` to `path` as strict JSON (`allow_nan=False`; `dumps`: more
    `json.dumps` options), through `replacing`, with a final newline."""
    text = json.dumps(json_ready(value), indent=indent, allow_nan=False, **dumps)
    write_text(path, text + "\n", sync)


def _finite(value):
    """(value with non-finite numbers as None, the reason or None)."""
    if isinstance(value, (np.ndarray, np.generic)):
        value = value.tolist()
    if isinstance(value, float):
        if math.isfinite(value):
            return value, None
        return None, "NaN" if math.isnan(value) else ("+Infinity" if value > 0 else "-Infinity")
    if isinstance(value, dict):
        out = {}
        for key, item in value.items():
            out[key], reason = _finite(item)
            if reason is not None:
                out[f"{key}_null_reason"] = reason
        return out, None
    if isinstance(value, (list, tuple)):
        items = [_finite(item) for item in value]
        reasons = [reason for _, reason in items if reason is not None]
        reason = (f"{len(reasons)} of {len(items)} entries not finite "
                  f"({', '.join(sorted(set(reasons)))})" if reasons else None)
        return [item for item, _ in items], reason
    return value, None


def _fsync(path: Path, flags: int) -> None:
    fd = os.open(path, flags)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
