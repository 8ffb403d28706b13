"""One progress display for a whole run: its phases in order, each from 0 to 100 %.

`RunProgress(RUN_PHASES)` (setup, dive, results, outputs; `plan`'s: `PLAN_PHASES`) draws `[2/4] dive  61 % t = 523 s`
on standard error. On a terminal it is one line rewritten in place (at most every
`REDRAW_S`); elsewhere (a CI log, a pipe) a line at each phase's start, at every `LOG_STEP` of
it and at its end, so a log stays short; disabled (`--quiet`), it prints nothing. A phase's
share only grows (an estimate that falls back is held) and stays below 100 % until the phase
ends: starting the next phase, `finish` or `close` ends it at 100 %, so the display reaches
100 % exactly when the work ends.
"""

from __future__ import annotations

import shutil
import sys
import time
from contextlib import contextmanager, nullcontext

REDRAW_S = 0.1  # s of wall time between two redraws of the terminal's line
LOG_STEP = 0.1  # share of a phase between two lines of a log
LOG_POLL_S = 1.0  # s of wall time between two estimates when the display is a log
# a mission run's (`drake-auv run`): load and plan, fly, read the dive back, write the files
RUN_PHASES = ("setup", "dive", "results", "outputs")
# `drake-auv plan`'s: the planner's stages, then every output file
PLAN_PHASES = ("plan", "outputs")
HELD = 0.999  # the most a phase shows before it ends (drawn as 99 %)
_SHOWN = {}  # stream -> the display running on it


def print_line(line: str, file=None) -> None:
    """Prints `line` on `file` (default standard error) without breaking the display running
    on that stream, if any (a warning during a run)."""
    file = sys.stderr if file is None else file
    shown = _SHOWN.get(file)
    if shown is None:
        print(line, file=file, flush=True)
    else:
        shown.write(line, file)


def phase_display(progress, phase: str, total: float, note: str = ""):
    """A context giving the display for work of `total` units called `phase`, begun with
    `note`: a caller's `RunProgress` that lists `phase` starts it (one display over the
    caller's phases), one that does not, or runs it already, counts these units in its current
    phase, and the caller's display is left open; anything else gets a display of this one
    phase, shown when `progress` is true, which ends with the context (where the work stopped
    if it failed)."""
    if isinstance(progress, RunProgress):
        if phase in progress.phases and phase != progress.phase:
            progress.start(phase, total, note)
        elif note:
            progress.update(progress.done, note)
        return nullcontext(progress)
    display = RunProgress((phase,), enabled=bool(progress))
    display.start(phase, total, note)
    return display


def track(items, phase: str, total: int | None = None, enabled: bool = True):
    """Yields `items`, counted on a display of one `phase` (a loop's progress: seeds, runs,
    steps); `total`: how many when `items` has no length."""
    total = len(items) if total is None else total
    with RunProgress((phase,), enabled=enabled) as display:
        display.start(phase, max(total, 1), f"{total} in all")
        for item in items:
            yield item
            display.advance(1)


class RunProgress:
    """The display of a run's `phases` (names, in the order they run) on `stream` (default
    standard error); `enabled` False prints nothing; `tty` None: whether `stream` is a
    terminal. `done`: the units of the current phase done."""

    def __init__(self, phases, stream=None, enabled: bool = True, tty: bool | None = None):
        self.phases = tuple(phases)
        if not self.phases:
            raise ValueError("RunProgress needs at least one phase")
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = bool(enabled)
        self.tty = bool(tty if tty is not None else getattr(self.stream, "isatty", bool)())
        self.phase: str | None = None
        self.share = 0.0
        self.note = ""
        self._total = 1.0
        self.done = 0.0
        self._drawn_at = -float("inf")
        self._logged = -1
        self._width = 0

    @classmethod
    def off(cls) -> RunProgress:
        """A display of a run's phases that prints nothing (a quiet run, a library call)."""
        return cls(RUN_PHASES, enabled=False)

    def start(self, phase: str, total: float = 1.0, note: str = "") -> None:
        """Ends the current phase at 100 % and begins `phase` (the next one of `phases`, or a
        later one when some are skipped), whose work counts `total` units."""
        if phase not in self.phases:
            raise ValueError(f"unknown phase {phase!r}; allowed: {', '.join(self.phases)}")
        if self.phase is not None:
            if self.phases.index(phase) <= self.phases.index(self.phase):
                raise ValueError(f"phase {phase!r} cannot follow {self.phase!r}: the phases "
                                 f"run in the order {', '.join(self.phases)}")
            if self.share < 1.0:
                self.note = ""
            self.finish()
        if not total > 0:
            raise ValueError(f"a phase's total must be > 0, got {total}")
        self.phase, self._total, self.done, self.share = phase, float(total), 0.0, 0.0
        self.note, self._logged = note, -1
        if self.enabled:
            _SHOWN[self.stream] = self
        self._draw(force=True)

    def due(self) -> bool:
        """Whether an `update` now would be drawn: a caller whose estimate costs something
        computes it only then."""
        return self.enabled and time.perf_counter() - self._drawn_at >= (
            REDRAW_S if self.tty else LOG_POLL_S)

    def update(self, done: float, note: str | None = None) -> None:
        """The current phase has `done` of its `total` units done (held below 100 % until the
        phase ends, and never lowered); `note`: what it is doing."""
        self.done = max(self.done, min(float(done), self._total))
        self.share = max(self.share, min(self.done / self._total, HELD))
        if note is not None:
            self.note = note
        self._draw(force=False)

    def advance(self, units: float = 1.0, note: str | None = None) -> None:
        """`units` more of the current phase done."""
        self.update(self.done + units, note)

    @contextmanager
    def step(self, note: str):
        """One unit of the current phase, named `note` while it runs (a log's line names the
        step that begins, with the share done before it)."""
        self.note = note
        self._draw(force=True)
        yield
        self.done = min(self.done + 1.0, self._total)
        self.share = max(self.share, min(self.done / self._total, HELD))
        if self.tty:
            self._draw(force=False)

    def write(self, line: str, file=None) -> None:
        """Prints `line` on `file` (default standard output) without breaking the display:
        the terminal's progress line is cleared first and drawn again at the next update."""
        if self.tty and self._width:
            self.stream.write("\r" + " " * self._width + "\r")
            self.stream.flush()
            self._width = 0
        print(line, file=file, flush=True)
        self._drawn_at = -float("inf")

    def finish(self, note: str | None = None) -> None:
        """Ends the current phase at 100 % (its work is over); `note`: what it did."""
        if self.phase is not None and self.share < 1.0:
            self.done, self.share = self._total, 1.0
            if note is not None:
                self.note = note
            self._draw(force=True)

    def close(self, completed: bool = True) -> None:
        """Ends the display: the current phase at 100 % when the run's work is over
        (`completed`), else where it stopped (an error, an interrupt)."""
        if self.phase is None:
            return
        if completed:
            self.finish()
        if self.enabled and self.tty:
            self.stream.write("\n")
            self.stream.flush()
        if _SHOWN.get(self.stream) is self:
            del _SHOWN[self.stream]
        self.phase = None

    def __enter__(self) -> RunProgress:
        return self

    def __exit__(self, kind, error, traceback) -> None:
        self.close(completed=kind is None)

    def text(self) -> str:
        """The display's line: the phase, its number, its share and its note."""
        k = self.phases.index(self.phase) + 1
        return (f"[{k}/{len(self.phases)}] {self.phase} {int(100 * self.share):3d} %"
                + (f" {self.note}" if self.note else ""))

    def _draw(self, force: bool) -> None:
        if not self.enabled or self.phase is None:
            return
        now = time.perf_counter()
        if self.tty:
            if not (force or self.share >= 1.0 or now - self._drawn_at >= REDRAW_S):
                return
            line = self.text()[:shutil.get_terminal_size().columns - 1]  # never wraps
            self.stream.write("\r" + line + " " * max(self._width - len(line), 0))
            self._width = len(line)
        else:
            tenth = int(self.share / LOG_STEP + 1e-9)
            if tenth <= self._logged:
                return
            self._logged = tenth
            self.stream.write(self.text() + "\n")
        self.stream.flush()
        self._drawn_at = now
