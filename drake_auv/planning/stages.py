"""One progress display over the named stages of a plan and the writing of its outputs (tqdm),
so that a command's bar reaches 100 % when its last file is written, not before."""

from __future__ import annotations


class StageBar:
    """A tqdm bar over `total` stages, drawn from its first stage on: the input checks before
    it print their one-line refusal or warning alone. A context manager; closing clears its
    line (on an error too)."""

    def __init__(self, total: int, desc: str = "plan", enabled: bool = True):
        self.total, self.desc, self.enabled = int(total), desc, bool(enabled)
        self._tqdm = None

    def _bar(self):
        if self._tqdm is None:
            from tqdm import tqdm

            self._tqdm = tqdm(total=self.total, desc=self.desc, unit="stage",
                              disable=not self.enabled, leave=False)
        return self._tqdm

    def update(self, n: int = 1) -> None:
        self._bar().update(n)

    def set_postfix_str(self, text: str) -> None:
        self._bar().set_postfix_str(text)

    def close(self) -> None:
        if self._tqdm is not None:
            self._tqdm.close()

    def __enter__(self) -> StageBar:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def stage_bar(progress, total: int, desc: str = "plan"):
    """(bar, owned): `progress` itself when it is a bar already (a caller's display over more
    stages), else a new `StageBar` over `total` stages, hidden unless `progress` is true; the
    caller closes a bar it owns."""
    if hasattr(progress, "update"):
        return progress, False
    return StageBar(total, desc, enabled=bool(progress)), True


def next_stage(bar, name: str | None = None) -> None:
    """Counts the running stage done and names the next one (None: the last was done)."""
    bar.update()
    if name is not None:
        bar.set_postfix_str(name)
