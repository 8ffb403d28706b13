"""Vectorised helpers for polylines: densify, resample, arc length and length (any dimension),
projection onto a 3D polyline, headings. The one place arc length and projection are computed."""

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


def arc_length(points: np.ndarray) -> np.ndarray:
    """(N,) cumulative distance along the polyline (N, d) from its first vertex."""
    seg = np.linalg.norm(np.diff(np.asarray(points, dtype=float), axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(seg)])


def resample(points: np.ndarray, spacing: float) -> np.ndarray:
    """Evenly spaced samples (at most `spacing` apart) along a polyline, ends included."""
    points = np.asarray(points, dtype=float)
    arc = arc_length(points)
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


class Polyline:
    """A polyline (M >= 2, 3) prepared for projections: `project(points)` gives the arclength
    (m) of the nearest point on it to each of `points` (..., 3), and the distance to it (m)."""

    def __init__(self, points: np.ndarray):
        points = np.asarray(points, dtype=float)
        self.a, self.ab = points[:-1], np.diff(points, axis=0)
        self.seg_sq = np.maximum(np.einsum("mk,mk->m", self.ab, self.ab), 1e-12)
        self.seg_len = np.sqrt(self.seg_sq)
        self.s0 = np.concatenate([[0.0], np.cumsum(self.seg_len)])[:-1]
        self.length = float(self.seg_len.sum())
        self.a_ab = np.einsum("mk,mk->m", self.a, self.ab)
        self.a_sq = np.einsum("mk,mk->m", self.a, self.a)
        self._ab_a = np.vstack([self.ab, -2.0 * self.a]).T  # (3, 2m): p.ab and -2 p.a at once

    def _nearest(self, flat: np.ndarray):
        """For points (n, 3): the nearest segment's index (n,), the parameter t (n, m) of
        every segment's nearest point and |p - nearest|^2 - |p|^2 (n, m)."""
        # |p - a - t ab|^2 = |p|^2 - 2 p.a + |a|^2 - 2 t (p - a).ab + t^2 |ab|^2 from one
        # (n, 3) x (3, 2m) product (the segments' a and ab are fixed); |p|^2 is the same for
        # every segment, so it is added after the nearest segment is chosen.
        m = len(self.a)
        products = flat @ self._ab_a
        u = products[:, :m] - self.a_ab  # (p - a).ab
        t = u / self.seg_sq
        np.minimum(t, 1.0, out=t)
        np.maximum(t, 0.0, out=t)
        gap = products[:, m:] + self.a_sq + t * (t * self.seg_sq - 2.0 * u)
        return np.argmin(gap, axis=1), t, gap

    def project(self, points: np.ndarray):
        flat = points.reshape(-1, 3)
        best, t, gap = self._nearest(flat)
        rows = np.arange(len(best))
        s = self.s0[best] + t[rows, best] * self.seg_len[best]
        gap_sq = gap[rows, best] + np.einsum("nk,nk->n", flat, flat)
        return (s.reshape(points.shape[:-1]),
                np.sqrt(np.maximum(gap_sq, 0.0)).reshape(points.shape[:-1]))

    def arclength(self, points: np.ndarray) -> np.ndarray:
        """`project`'s arclength alone (m), without the distance."""
        flat = points.reshape(-1, 3)
        best, t, _ = self._nearest(flat)
        s = self.s0[best] + t[np.arange(len(best)), best] * self.seg_len[best]
        return s.reshape(points.shape[:-1])


def polyline_progress(points: np.ndarray, polyline: np.ndarray):
    """Arclength along `polyline` (M >= 2, 3) of the nearest point to each of `points`
    (..., 3), and the distance to it, m."""
    return Polyline(polyline).project(np.asarray(points, dtype=float))


def project(points: np.ndarray, polyline: np.ndarray):
    """Arclength along `polyline` (M >= 2, 3) of the nearest point to each of `points`
    (..., 3), and the distance to it, m."""
    return Polyline(polyline).project(np.asarray(points, dtype=float))
