"""A campaign's output folder: checked before any work, and held by one campaign at a time.

`check_output` reads only (nothing is created): the folder, or its nearest existing parent,
must be a writable folder and no name the campaign writes may be taken by a folder.
`locked(out)` creates the folder and takes an exclusive `fcntl.flock` on `OUT/.lock` for the
whole campaign, so a second campaign into the same folder is refused at once instead of
writing every run a second time. The lock file is kept (removing it would let a third
campaign lock a new file while the second still holds the old one); the kernel releases the
lock when the process ends, however it ends.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
from pathlib import Path

from drake_auv.campaign.engine import CampaignError
from drake_auv.campaign.task import one_line

LOCK_FILE = ".lock"
OUTPUTS = ("campaign.json", "results.csv", "summary.md", "summary.json", "coverage.png",
           "clearance.png", "variants.png", LOCK_FILE)


def check_output(out, outputs=OUTPUTS) -> None:
    """Raises CampaignError (one line) when `out` cannot hold a campaign's files (`outputs`:
    their names)."""
    out = Path(out)
    allowed = "allowed: a writable folder, new or holding this campaign"
    if out.exists() and not out.is_dir():
        raise CampaignError(f"-o {out}: is a file, not a folder; {allowed}")
    parent = out
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise CampaignError(f"-o {out}: {parent} is a file, not a folder; {allowed}")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise CampaignError(f"-o {out}: {parent} is not writable; {allowed}")
    for name in outputs:
        path = out / name
        if path.exists() and not path.is_file():
            raise CampaignError(f"-o {out}: {path} is a folder, not a file; {allowed}")
        if path.exists() and not os.access(path, os.W_OK):
            raise CampaignError(f"-o {out}: {path} is not writable; {allowed}")


@contextlib.contextmanager
def locked(out):
    """Creates `out` and holds an exclusive lock on it; CampaignError (one line) when another
    campaign holds it or the folder cannot be written."""
    out = Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
        handle = open(os.open(out / LOCK_FILE, os.O_WRONLY | os.O_APPEND | os.O_CREAT
                              | os.O_NOFOLLOW, 0o666), "a")
    except OSError as err:
        raise CampaignError(f"-o {out}: cannot write there ({one_line(err)}); allowed: a "
                            "writable folder") from None
    try:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise CampaignError(f"-o {out}: another campaign is running into this folder "
                                f"(it holds {out / LOCK_FILE}); allowed: wait for it to end "
                                "(then rerun to add runs) or another -o folder") from None
        yield out
    finally:
        handle.close()  # releases the lock
