"""No-go zones (moorings, piers, cables) for the planners: the zones grown by a clearance
(Omega) are forbidden to every lane, contour and transit, and transits go around them.

Routing: the shortest path in the plane around the forbidden set, on its visibility graph.
The nodes are the vertices of a routing shell, the forbidden set grown by a small margin and
simplified (by at most half the margin, so the shell stays outside the forbidden set); two
nodes are linked when the segment between them does not meet the forbidden set; Dijkstra
(scipy) finds the path. Nodes outside the grid are left out, so detours stay over the grid.
A target that no detour reaches (a zone cutting the grid in two) is reported as unreachable.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra


class NoGo:
    """Forbidden set and detours, world frame (m).

    Args:
        zones: shapely (Multi)Polygon of the no-go zones, world frame.
        clearance: distance to keep from them, m (> 0; the planner's Omega).
        extent: (xmin, xmax, ymin, ymax) of the grid; routing nodes outside it are dropped.
    """

    def __init__(self, zones, clearance: float, extent=None):
        import shapely

        if not (np.isfinite(clearance) and clearance > 0):
            raise ValueError(f"no-go clearance must be > 0 m, got {clearance}")
        self.zones = zones
        self.clearance = float(clearance)
        self.forbidden = zones.buffer(clearance, quad_segs=16)
        shapely.prepare(self.forbidden)
        margin = max(0.05 * clearance, 1e-3)
        shell = self.forbidden.buffer(margin, quad_segs=4).simplify(0.5 * margin)
        rings = [shell] if shell.geom_type == "Polygon" else list(shell.geoms)
        nodes = np.vstack([np.asarray(r.coords)[:-1] for p in rings
                           for r in (p.exterior, *p.interiors)])
        if extent is not None:
            xmin, xmax, ymin, ymax = extent
            keep = ((nodes[:, 0] >= xmin) & (nodes[:, 0] <= xmax) & (nodes[:, 1] >= ymin)
                    & (nodes[:, 1] <= ymax))
            nodes = nodes[keep]
        self.nodes = nodes
        i, j = np.triu_indices(len(nodes), 1)
        ok = self._clear(nodes[i], nodes[j])
        self._edges = (i[ok], j[ok], np.linalg.norm(nodes[i[ok]] - nodes[j[ok]], axis=1))

    def copy(self) -> "NoGo":
        """The same zones and routing graph with a forbidden set of its own: a prepared GEOS
        geometry is for one thread at a time (the planner routes its lawnmower on another)."""
        import copy

        import shapely

        other = copy.copy(self)
        other.forbidden = shapely.from_wkb(shapely.to_wkb(self.forbidden))
        shapely.prepare(other.forbidden)
        return other

    def inside(self, xy) -> np.ndarray:
        """(N,) True where a world point lies in the forbidden set (boundary included)."""
        import shapely

        xy = np.atleast_2d(np.asarray(xy, float))
        return shapely.intersects_xy(self.forbidden, xy[:, 0], xy[:, 1])

    def _clear(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """(N,) True where the segment a-b does not meet the forbidden set."""
        import shapely

        if len(a) == 0:
            return np.zeros(0, dtype=bool)
        return ~shapely.intersects(self.forbidden, shapely.linestrings(np.stack([a, b], axis=1)))

    def detour(self, a, b) -> np.ndarray | None:
        """(K, 2) shortest xy polyline from a to b (ends included) outside the forbidden set;
        [a, b] when the straight line is clear, None when no detour exists."""
        a, b = np.asarray(a, float)[:2], np.asarray(b, float)[:2]
        if self._clear(a[None], b[None])[0]:
            return np.vstack([a, b])
        v = len(self.nodes)
        if v == 0:
            return None
        ia = self._clear(np.repeat(a[None], v, axis=0), self.nodes)
        ib = self._clear(np.repeat(b[None], v, axis=0), self.nodes)
        i, j, w = self._edges
        ni, nb = np.flatnonzero(ia), np.flatnonzero(ib)
        rows = np.concatenate([i, np.full(len(ni), v), nb])
        cols = np.concatenate([j, ni, np.full(len(nb), v + 1)])
        wts = np.concatenate([w, np.linalg.norm(self.nodes[ni] - a, axis=1),
                              np.linalg.norm(self.nodes[nb] - b, axis=1)])
        graph = coo_matrix((wts, (rows, cols)), shape=(v + 2, v + 2)).tocsr()
        dist, pred = dijkstra(graph, directed=False, indices=v, return_predecessors=True)
        if not np.isfinite(dist[v + 1]):
            return None
        chain = [v + 1]
        while chain[-1] != v:
            chain.append(int(pred[chain[-1]]))
        pts = np.vstack([a, self.nodes[[k for k in chain[::-1] if k < v]], b])
        return pts
