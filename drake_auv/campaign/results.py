"""`results.csv`, crash-safe: one row per finished run, appended and fsync'ed at once.

Only the client process writes (rows arrive from the workers as task results), so a worker
killed mid-run can neither lose nor duplicate a row. The header is written once, with the
file; a rerun reads the rows already there (their keys: seed and the varied values, as typed)
and runs only the missing ones. A last line cut short by a crash is dropped before appending.
"""

from __future__ import annotations

import csv
import io
import os
from pathlib import Path

from drake_auv.campaign.task import METRICS, TIMING


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
    """`path` (results.csv) with the columns of `vary_keys`; creates it with its header."""

    def __init__(self, path, vary_keys):
        self.path = Path(path)
        self.vary_keys = list(vary_keys)
        self.columns = columns(self.vary_keys)
        self.path.parent.mkdir(parents=True, exist_ok=True)
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

    def rows(self) -> list[dict]:
        """Every row written, as text."""
        with open(self.path, newline="") as f:
            return list(csv.DictReader(f))

    def done(self) -> set[tuple]:
        """Keys of the runs already written (ok or failed)."""
        return {(r["seed"], *(r[k] for k in self.vary_keys)) for r in self.rows()}

    def append(self, key: tuple, row: dict) -> None:
        """Writes the row of run `key` (seed, values) and syncs it to disk."""
        values = dict(zip(["seed", *self.vary_keys], key), **row)
        buffer = io.StringIO()
        csv.writer(buffer, lineterminator="\n").writerow(
            [_text(values.get(c)) for c in self.columns])
        self._append(buffer.getvalue())

    def _append(self, text: str) -> None:
        with open(self.path, "a", newline="") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
