"""The project's one compiler: numba, for the few inner loops that numpy cannot vectorise
without doing many times the work (a search that stops early, a recursion over a polyline).

`kernel(fn)` compiles `fn` on its first call, in nopython mode without the GIL, so
`resources.map_chunks` runs it on the usable cores. The machine code is cached beside the
source (in the user's cache directory where that is read-only, `NUMBA_CACHE_DIR` to choose),
so only a fresh install pays the compilation: `benchmarks/bench_jit.py` measures both, and
each kernel against the numpy or scipy code it replaces.
"""

from __future__ import annotations

import numba


def kernel(fn):
    """`fn` compiled by numba (nopython, nogil, cached; numpy's error model: a float
    division by zero gives inf or NaN, as in numpy)."""
    return numba.njit(nogil=True, cache=True, error_model="numpy")(fn)
