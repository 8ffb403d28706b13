"""`results.csv`, crash-safe: one row per finished run, appended and fsync'ed at once.

Only the client process writes (rows arrive from the workers as task results), so a worker
killed mid-run can neither lose nor duplicate a row. The header is written once, with the
file; a rerun reads the rows already there (their keys: seed and the varied values, as typed;
the mission is the folder's, checked against `campaign.json`) and runs only the missing ones.
A key is written once: `append` refuses a key already there, a file holding a key twice
(written by two campaigns at once before the folder was locked) is rewritten with the first
row of each key, and `drop` removes rows (failed ones to run again) by an atomic rewrite. A
last line cut short by a crash is dropped before appending.
"""

from __future__ import annotations

import csv
import io
import os
from pathlib import Path

from drake_auv.campaign.task import METRICS, TIMING
from drake_auv.output_files import open_replacing


def columns(vary_keys) -> list[str]:
    """The header: seed, one column per varied key, status, the metrics, timing, error."""
    return ["seed", *vary_keys, "status", *METRICS, *TIMING, "error"]


def _text(value) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


class ResultsFile:
    """`path` (results.csv) with the columns of `vary_keys` (or `header`: the same names in
    another order, other metrics); creates it with its header, or checks that it can be
    appended to."""

    def __init__(self, path, vary_keys, header=None):
        self.path = Path(path)
        self.vary_keys = list(vary_keys)
        self.columns = list(header) if header is not None else columns(self.vary_keys)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        if self.path.is_symlink():
            raise ValueError(f"{self.path} is a symbolic link; allowed: a regular file or none "
                             "(nothing is read or written through a link)")
        if not self.path.exists() or self.path.stat().st_size == 0:
            self._append(",".join(self.columns) + "\n")
            return
        data = self.path.read_bytes()
        if not data.endswith(b"\n"):  # a row cut short by a crash: drop it
            with open(self.path, "r+b") as f:
                f.truncate(data.rfind(b"\n") + 1)
                os.fsync(f.fileno())
        header = data.split(b"\n", 1)[0].decode()
        if header.split(",") != self.columns:
            raise ValueError(f"{self.path}: written by another campaign (columns {header}); "
                             f"allowed: the same --vary keys ({', '.join(self.vary_keys)}) "
                             "or another -o folder")
        rows = self.rows()
        unique = {self.key(r): r for r in reversed(rows)}  # the first row of each key wins
        if len(unique) < len(rows):
            self._rewrite([r for r in rows if unique[self.key(r)] is r])
        self._append("")  # appendable (its folder and its permissions), before any work

    def key(self, row: dict) -> tuple:
        """A row's key: (seed, the varied values), as text."""
        return (row["seed"], *(row[k] for k in self.vary_keys))

    def rows(self) -> list[dict]:
        """Every row written, as text (one per key)."""
        with open(self.path, newline="") as f:
            return list(csv.DictReader(f))

    def done(self) -> set[tuple]:
        """Keys of the runs already written (ok or failed)."""
        return {self.key(r) for r in self.rows()}

    def failed(self) -> set[tuple]:
        """Keys of the runs written as failed."""
        return {self.key(r) for r in self.rows() if r["status"] == "failed"}

    def drop(self, keys) -> int:
        """Removes the rows of `keys` (an atomic rewrite); returns how many were removed."""
        keys = set(keys)
        rows = self.rows()
        kept = [r for r in rows if self.key(r) not in keys]
        if len(kept) < len(rows):
            self._rewrite(kept)
        return len(rows) - len(kept)

    def append(self, key: tuple, row: dict) -> None:
        """Writes the row of run `key` (seed, values) and syncs it to disk; ValueError when
        the key is already written (the folder's lock makes this process the only writer)."""
        key = tuple(str(k) for k in key)
        if key in self.done():
            raise ValueError(f"{self.path}: the run {key} is already written; allowed: one "
                             "row per run (drop it first to run it again)")
        self._append(self._line(dict(zip(["seed", *self.vary_keys], key), **row)))

    def _line(self, values: dict) -> str:
        buffer = io.StringIO()
        csv.writer(buffer, lineterminator="\n").writerow(
            [_text(values.get(c)) for c in self.columns])
        return buffer.getvalue()

    def _rewrite(self, rows) -> None:
        """Replaces the file by its header and `rows` (text): a synced temporary file renamed
        over it, so a crash leaves the old file or the new one, never a mix."""
        with open_replacing(self.path, "w", sync=True, newline="") as f:
            f.write(",".join(self.columns) + "\n")
            f.writelines(self._line(r) for r in rows)

    def _append(self, text: str) -> None:
        fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_NOFOLLOW, 0o666)
        with open(fd, "a", newline="") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
