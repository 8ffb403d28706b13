"""The machine's memory, asked before a large allocation (pure Python).

`check_memory(need, what)` refuses, in one ValueError line with the figure and the limit, work
whose predicted memory exceeds what the machine has available now (Linux's `MemAvailable`,
else the physical pages free), instead of failing later with a `MemoryError` or being killed.
"""

from __future__ import annotations

import os

MiB, GiB = 2 ** 20, 2 ** 30


def available_memory() -> int:
    """Bytes of memory available to a new allocation now."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")


def check_memory(need_bytes: float, what: str) -> None:
    """ValueError naming `what` when `need_bytes` exceed the memory available now."""
    available = available_memory()
    if need_bytes > available:
        raise ValueError(f"{what} needs {_size(need_bytes)} of memory, more than the "
                         f"{_size(available)} available on this machine")


def _size(n: float) -> str:
    return f"{n / GiB:.3g} GiB" if n >= GiB else f"{n / MiB:.3g} MiB"
