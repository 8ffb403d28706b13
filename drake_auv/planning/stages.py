"""One progress display over the named stages of a plan and the writing of its outputs (tqdm),
so that a command's bar reaches 100 % when its last file is written, not before."""

from __future__ import annotations


def stage_bar(progress, total: int, desc: str = "plan"):
    """(bar, owned): `progress` itself when it is a tqdm bar already (a caller's display over
    more stages), else a new bar over `total` stages, hidden unless `progress` is true; the
    caller closes a bar it owns."""
    if hasattr(progress, "update"):
        return progress, False
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="stage", disable=not progress, leave=False), True


def next_stage(bar, name: str | None = None) -> None:
    """Counts the running stage done and names the next one (None: the last was done)."""
    bar.update()
    if name is not None:
        bar.set_postfix_str(name)
