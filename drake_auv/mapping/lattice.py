"""Integer codes of 3D lattice indices (voxels, tiles, grid nodes): one int64 per index, 21
bits an axis, so sets of them are sorted int64 arrays, looked up by binary search."""

from __future__ import annotations

import numpy as np

OFFSET = 1 << 20  # index offset: indices in [-2^20, 2^20) encode as non-negative fields
_MASK = (1 << 21) - 1


def encode(idx: np.ndarray) -> np.ndarray:
    """(n,) codes of integer lattice indices (n, 3); ordered as the indices (x, then y, z)."""
    idx = idx.astype(np.int64) + OFFSET
    return (idx[:, 0] << 42) | (idx[:, 1] << 21) | idx[:, 2]


def decode(codes: np.ndarray) -> np.ndarray:
    """(n, 3) int64 lattice indices of `codes` (n,)."""
    return np.stack([(codes >> 42) & _MASK, (codes >> 21) & _MASK, codes & _MASK],
                    axis=1) - OFFSET


def unique(codes: np.ndarray) -> np.ndarray:
    """The sorted distinct values of integer `codes` (n,), as `np.unique` gives them: a sort
    and one comparison, 2-3x faster than numpy 2's hashing `np.unique` on the hundreds to
    thousands of codes of a scan or a box."""
    codes = np.sort(codes)
    if len(codes) < 2:
        return codes
    distinct = np.empty(len(codes), bool)
    distinct[0] = True
    np.not_equal(codes[1:], codes[:-1], out=distinct[1:])
    return codes[distinct]


def in_sorted(sorted_codes: np.ndarray, codes: np.ndarray) -> np.ndarray:
    """(n,) whether each of `codes` (n,) is in `sorted_codes` (sorted, unique)."""
    if len(sorted_codes) == 0:
        return np.zeros(len(codes), bool)
    at = np.minimum(np.searchsorted(sorted_codes, codes), len(sorted_codes) - 1)
    return sorted_codes[at] == codes


def in_box(points: np.ndarray, lo, hi) -> np.ndarray:
    """(n,) whether each of `points` (n, 3) lies in the box [lo, hi] (3,), bounds included;
    column by column, 6x faster than `np.all(..., axis=1)` on the replanner's boxes."""
    (x0, y0, z0), (x1, y1, z1) = np.asarray(lo, float).tolist(), np.asarray(hi, float).tolist()
    x, y, z = points[:, 0], points[:, 1], points[:, 2]
    return (x >= x0) & (x <= x1) & (y >= y0) & (y <= y1) & (z >= z0) & (z <= z1)
