"""The machine's memory and cores (pure Python).

`check_memory(need, what)` refuses, in one ValueError line with the figure and the limit, work
whose predicted memory exceeds what the machine has available now (Linux's `MemAvailable`,
else the physical pages free), instead of failing later with a `MemoryError` or being killed.

`map_chunks(fn, n, chunk)` spreads an inner loop over the usable cores, chunk by chunk, for
loops whose chunks spend their time in code that releases the GIL (numpy on large arrays,
scipy's KD-trees, Embree). The results come back in chunk order and each chunk is computed
alone, so the outcome does not depend on the number of cores.

`keep_freed_memory()` has glibc's malloc keep the memory a program frees for its next
allocations, and `quick_gil_handoff()` has a thread waiting for the GIL get it sooner
(`drake-auv plan` run as the program asks for both: `tune_batch_process`).
"""

from __future__ import annotations

import ctypes
import gc
import os
import threading
from concurrent.futures import ThreadPoolExecutor

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


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity, else the machine's count)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


_POOL: ThreadPoolExecutor | None = None
_POOL_LOCK = threading.Lock()


def _pool() -> ThreadPoolExecutor:
    """The process's worker threads, one per usable core, started on first use."""
    global _POOL
    with _POOL_LOCK:
        if _POOL is None:
            _POOL = ThreadPoolExecutor(usable_cores(), thread_name_prefix="drake_auv-chunks")
        return _POOL


class paused_gc:
    """Context in which the cyclic garbage collector does not run, for work spread over
    threads: it then never runs on a worker (Drake objects must be freed on the thread that
    made them), only where the last pause ends. Nests, and pauses taken on several threads
    overlap; reference counting frees objects as usual."""

    _depth = 0
    _was_enabled = False
    _lock = threading.Lock()

    def __enter__(self):
        with paused_gc._lock:
            if paused_gc._depth == 0:
                paused_gc._was_enabled = gc.isenabled()
                gc.disable()
            paused_gc._depth += 1
        return self

    def __exit__(self, *exc) -> None:
        with paused_gc._lock:
            paused_gc._depth -= 1
            if paused_gc._depth == 0 and paused_gc._was_enabled:
                gc.enable()


def map_chunks(fn, n: int, chunk: int) -> list:
    """[fn(slice(k, k + chunk)) for k in range(0, n, chunk)], the chunks run on the usable
    cores when there are several of each, with the garbage collector paused (`paused_gc`).
    On a worker thread the chunks run in turn there."""
    slices = [slice(k, min(k + chunk, n)) for k in range(0, n, chunk)]
    if len(slices) < 2 or usable_cores() < 2 or threading.current_thread().name.startswith(
            "drake_auv-chunks"):
        return [fn(s) for s in slices]
    with paused_gc():
        return list(_pool().map(fn, slices))


def keep_freed_memory() -> None:
    """Has glibc's malloc serve every allocation from its heap and keep what is freed there
    (no mmap, no trim) instead of handing large blocks back to the system: the planner and
    its metrics allocate and free arrays of 10-400 MB thousands of times, and each time the
    system maps and zeroes the pages afresh (a fifth of a 4 M-cell plan's time on a virtual
    machine: docs/benchmarks.md). The process's memory then stays at its peak. For a
    program's own process, not a library caller's; a no-op off glibc."""
    try:
        libc = ctypes.CDLL("libc.so.6")
    except OSError:
        return
    m_trim_threshold, m_mmap_max = -1, -4  # from glibc's malloc.h
    libc.mallopt(m_mmap_max, 0)
    libc.mallopt(m_trim_threshold, 2 ** 31 - 1)


def quick_gil_handoff(interval: float = 0.0005) -> None:
    """Has a thread that waits for the GIL get it after `interval` seconds rather than
    CPython's 5 ms: threads that make many short numpy calls (the plan's metrics, each call
    releasing and taking the GIL back) would otherwise wait up to 5 ms before each one while
    another thread runs Python (the figures, the GeoJSON): `benchmarks/bench_gil_handoff.py`,
    figures in docs/benchmarks.md. For a program's own process: it sets the interpreter's
    `sys.setswitchinterval`."""
    import sys

    sys.setswitchinterval(interval)


def tune_batch_process() -> None:
    """A batch program's own process (`drake-auv plan`): `keep_freed_memory` and
    `quick_gil_handoff`."""
    keep_freed_memory()
    quick_gil_handoff()
