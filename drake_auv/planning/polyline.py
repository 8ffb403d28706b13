"""Vectorised helpers for polylines (any dimension): densify, length, headings."""

from __future__ import annotations

import numpy as np


def densify(points: np.ndarray, spacing: float) -> np.ndarray:
    """Inserts samples so no segment is longer than `spacing`; keeps every original vertex."""
    points = np.asarray(points, dtype=float)
    if len(points) < 2:
        return points.copy()
    seg = np.diff(points, axis=0)
    counts = np.maximum(np.ceil(np.linalg.norm(seg, axis=1) / spacing - 1e-9).astype(int), 1)
    idx = np.repeat(np.arange(len(seg)), counts)
    first = np.repeat(np.cumsum(counts) - counts, counts)
    frac = (np.arange(counts.sum()) - first) / np.repeat(counts, counts)
    out = points[idx] + frac[:, None] * seg[idx]
    return np.vstack([out, points[-1:]])


def resample(points: np.ndarray, spacing: float) -> np.ndarray:
    """Evenly spaced samples (at most `spacing` apart) along a polyline, ends included."""
    points = np.asarray(points, dtype=float)
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(seg)])
    total = arc[-1]
    if total <= 0:
        return points[:1].copy()
    n = max(2, int(np.ceil(total / spacing - 1e-9)) + 1)
    s = np.linspace(0.0, total, n)
    return np.column_stack([np.interp(s, arc, points[:, k]) for k in range(points.shape[1])])


def length(points: np.ndarray) -> float:
    """Total length of a polyline."""
    return float(np.linalg.norm(np.diff(np.asarray(points, float), axis=0), axis=1).sum())


def motion_heading(points: np.ndarray, fallback: float = 0.0,
                   min_horizontal: float = 0.0) -> np.ndarray:
    """(N,) yaw of the horizontal direction of motion at each sample (the next segment's; the
    last sample keeps the previous one; a vertical or zero move keeps the previous heading).

    `min_horizontal` in [0, 1): a segment whose horizontal length is at most that share of its
    3D length counts as vertical (a climb of 2.5 m with 6 cm of drift has no direction worth
    turning to)."""
    points = np.asarray(points, dtype=float)
    n = len(points)
    if n < 2:
        return np.full(n, fallback)
    d = np.diff(points[:, :2], axis=0)
    horizontal = np.linalg.norm(d, axis=1)
    moving = horizontal > 1e-9
    if min_horizontal > 0.0:
        moving &= horizontal > min_horizontal * np.linalg.norm(np.diff(points, axis=0), axis=1)
    yaw = np.arctan2(d[:, 1], d[:, 0])
    # Carry the last valid yaw forward over stationary or vertical segments.
    idx = np.where(moving, np.arange(len(d)), -1)
    idx = np.maximum.accumulate(idx)
    first = np.flatnonzero(moving)
    start = yaw[first[0]] if first.size else fallback
    out = np.where(idx >= 0, yaw[np.maximum(idx, 0)], start)
    return np.append(out, out[-1])
