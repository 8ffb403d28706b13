"""The mission's vector logs streamed to disk as the dive runs, so their memory does not grow
with it.

A `VectorLogSink` keeps every sample in memory: on `monterey_wall` the 10 Hz logs of the true
and estimated state, the reference and the profile grow by 12.8 MB per simulated hour. The
runner's Simulator monitor calls `LogSpool.spool`, which every `period_s` of simulated time
appends each log's samples to a temporary file of its own (rows of time and values, float64)
and clears the log, so memory holds at most one period's samples of each. `LogSpool.read`
gives a log's whole dive back (the file's rows, then what the log holds) as a `SpooledLog`,
which reads as a `VectorLog` does (`sample_times()`, `data()`). The files are deleted when the
spool is closed or collected.
"""

from __future__ import annotations

import tempfile

import numpy as np


class SpooledLog:
    """A log's samples over the whole dive: `sample_times()` (n,), s, and `data()` (size, n),
    as `VectorLog` gives them."""

    def __init__(self, times: np.ndarray, data: np.ndarray):
        self._times, self._data = times, data

    def sample_times(self) -> np.ndarray:
        return self._times

    def data(self) -> np.ndarray:
        return self._data


class LogSpool:
    """Moves the samples of `sinks` ({name: `VectorLogSink`}) of one root Context to disk every
    `period_s` (s of simulated time, > 0)."""

    def __init__(self, sinks: dict, period_s: float = 300.0):
        if not (np.isfinite(period_s) and period_s > 0):
            raise ValueError(f"the log spool's period must be a finite time > 0 s, got "
                             f"{period_s}")
        self.sinks, self.period_s = dict(sinks), float(period_s)
        self._files = {name: tempfile.TemporaryFile(prefix=f"drake_auv_{name}_log_")
                       for name in self.sinks}
        self._due = self.period_s

    def spool(self, root_context) -> None:
        """Appends every log's samples to its file and clears the log, once `period_s` has
        passed since the last time (else nothing: the monitor calls this every step)."""
        now = root_context.get_time()
        if now < self._due:
            return
        self._due = now + self.period_s
        for name, sink in self.sinks.items():
            log = sink.FindMutableLog(root_context)
            if log.num_samples():
                rows = np.vstack([log.sample_times()[None], log.data()]).T
                rows.tofile(self._files[name])
                log.Clear()

    def read(self, name: str, root_context) -> SpooledLog:
        """The log `name`'s samples since the start: the spooled ones, then the log's own."""
        sink, spooled = self.sinks[name], self._files[name]
        log = sink.FindLog(root_context)
        spooled.flush()
        spooled.seek(0)
        rows = np.fromfile(spooled, dtype=float).reshape(-1, log.get_input_size() + 1)
        return SpooledLog(np.concatenate([rows[:, 0], log.sample_times()]),
                          np.hstack([rows[:, 1:].T, log.data()]))

    def close(self) -> None:
        """Deletes the files."""
        for spooled in self._files.values():
            spooled.close()
