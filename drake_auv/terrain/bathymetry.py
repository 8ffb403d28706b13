"""A regular bathymetric grid: elevation z(x, y) in the world frame (z up, metres).

Cell (i, j) (row i, column j) has its centre at x = origin[0] + j * spacing[0],
y = origin[1] + i * spacing[1]: rows run along +y (south to north once a reader has fixed the
row order), columns along +x. NaN marks no-data cells, which planners treat as no-go.
`crs` and `transform` keep the georeferencing of the source file so exports can go back to it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


# m: the Earth's elevations, from below its deepest trench to above its highest peak
ELEVATION_RANGE_M = (-11_500.0, 9_000.0)


def elevation_problem(z: np.ndarray, of: str = "") -> str | None:
    """None when every cell of `z` is NaN (no-data) or a finite elevation in ELEVATION_RANGE_M;
    else one line naming the bad cells, the first one's value and (row, column) `of` the grid,
    and the allowed range. An undeclared no-data value (-1e30, -3.4e38) lands here instead of
    being planned on as a seabed."""
    lo, hi = ELEVATION_RANGE_M
    with np.errstate(invalid="ignore"):
        infinite, outside = np.isinf(z), (z < lo) | (z > hi)
    bad = infinite if infinite.any() else outside
    if not bad.any():
        return None
    i, j = np.argwhere(bad)[0]
    what = "infinite cell(s)" if infinite.any() else f"cell(s) outside [{lo:g}, {hi:g}] m"
    return (f"{int(bad.sum())} {what} (first {z[i, j]:g} at row {i}, column {j}{of}); "
            f"elevations must be finite metres in [{lo:g}, {hi:g}] (z up), no-data cells NaN "
            "or the file's nodata value")


@dataclass(frozen=True)
class Bathymetry:
    """Elevation grid in metres, NaN for no-data.

    Attributes:
        z: (ny, nx) elevations, m (negative below sea level).
        spacing: (dx, dy) ground cell size, m, both > 0.
        origin: (x0, y0) world position of the centre of cell (0, 0), m.
        crs: the source coordinate reference system (e.g. "EPSG:3857"), or None.
        to_crs: 3x3 affine matrix taking world (x, y, 1) to source-CRS coordinates, or None.
            It undoes any ground-metre scaling, so exports land in the file's CRS.
    """

    z: np.ndarray
    spacing: tuple[float, float] = (1.0, 1.0)
    origin: tuple[float, float] = (0.0, 0.0)
    crs: str | None = None
    to_crs: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self):
        z = np.array(self.z, dtype=float)
        if z.ndim != 2:
            raise ValueError(f"Bathymetry.z must be a 2D grid, got shape {z.shape}")
        if z.shape[0] < 3 or z.shape[1] < 3:
            raise ValueError(f"Bathymetry grid must be at least 3 x 3 cells, got {z.shape}")
        problem = elevation_problem(z)
        if problem is not None:
            raise ValueError(f"Bathymetry.z holds {problem}")
        if np.isnan(z).all():
            raise ValueError("Bathymetry.z is all no-data (NaN)")
        spacing = tuple(float(s) for s in self.spacing)
        if len(spacing) != 2 or not all(np.isfinite(s) and s > 0 for s in spacing):
            raise ValueError(f"Bathymetry.spacing must be two cell sizes > 0 m, got {self.spacing}")
        origin = tuple(float(o) for o in self.origin)
        if len(origin) != 2 or not all(np.isfinite(origin)):
            raise ValueError(f"Bathymetry.origin must be two finite numbers, got {self.origin}")
        z.setflags(write=False)
        object.__setattr__(self, "z", z)
        object.__setattr__(self, "spacing", spacing)
        object.__setattr__(self, "origin", origin)

    @property
    def shape(self) -> tuple[int, int]:
        return self.z.shape

    @property
    def x(self) -> np.ndarray:
        """(nx,) cell-centre x coordinates, m."""
        return self.origin[0] + self.spacing[0] * np.arange(self.z.shape[1])

    @property
    def y(self) -> np.ndarray:
        """(ny,) cell-centre y coordinates, m."""
        return self.origin[1] + self.spacing[1] * np.arange(self.z.shape[0])

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(xmin, xmax, ymin, ymax) of the cell centres, m."""
        return (self.x[0], self.x[-1], self.y[0], self.y[-1])

    @property
    def valid(self) -> np.ndarray:
        """(ny, nx) True where the cell holds data."""
        return np.isfinite(self.z)

    def elevation_at(self, x, y) -> np.ndarray:
        """Bilinear elevation at world points (clamped to the grid), m; NaN next to no-data."""
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        ny, nx = self.z.shape
        fj = np.clip((x - self.origin[0]) / self.spacing[0], 0, nx - 1)
        fi = np.clip((y - self.origin[1]) / self.spacing[1], 0, ny - 1)
        j0 = np.minimum(np.floor(fj).astype(int), nx - 2)
        i0 = np.minimum(np.floor(fi).astype(int), ny - 2)
        tj, ti = fj - j0, fi - i0
        z = self.z
        return ((1 - ti) * ((1 - tj) * z[i0, j0] + tj * z[i0, j0 + 1])
                + ti * ((1 - tj) * z[i0 + 1, j0] + tj * z[i0 + 1, j0 + 1]))

    def world_to_crs(self, xy) -> np.ndarray:
        """(N, 2) world points to the source CRS (identity when no transform is known)."""
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        if self.to_crs is None:
            return xy.copy()
        homog = np.hstack([xy, np.ones((len(xy), 1))])
        return (homog @ np.asarray(self.to_crs, dtype=float).T)[:, :2]

    def with_z(self, z: np.ndarray) -> "Bathymetry":
        """A copy on the same grid and georeferencing with other elevations."""
        return Bathymetry(z, self.spacing, self.origin, self.crs, self.to_crs)
