"""PNG figures of a `CoveragePlan`, like the reference's Figures 76 to 80.

Plan views are drawn in the world frame (ground metres, equal aspect); with a `GeoFrame` their
axes read the grid's CRS coordinates (where the grid is not rotated in it), latitude and
longitude are marked where the meridians and parallels cross the top and right edges, and an
arrow points to true north. Uses `matplotlib.figure.Figure` directly (no pyplot, no display
backend needed).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure

from drake_auv.output_files import replacing

DRAWN_VERTICES = 250_000  # a path line's most vertices on a figure (`label_runs`)
LABEL_COLOURS = {"planar": "tab:blue", "slice": "tab:red", "transit": "0.6", "lawnmower": "tab:green"}


def _extent(bathy):
    dx, dy = bathy.spacing
    xmin, xmax, ymin, ymax = bathy.extent
    return (xmin - dx / 2, xmax + dx / 2, ymin - dy / 2, ymax + dy / 2)


def _plan_axes(fig, bathy, title, geo=None):
    ax = fig.add_subplot(1, 1, 1)
    ax.set_aspect("equal")
    ax.set_title(title)
    e = _extent(bathy)
    ax.set_xlim(e[0], e[1])
    ax.set_ylim(e[2], e[3])
    if geo is None:
        ax.set_xlabel("x (m, grid frame)")
        ax.set_ylabel("y (m, grid frame)")
    else:
        _georeference(ax, geo, e)
    return ax


def _crs_name(geo) -> str:
    epsg = geo.crs.to_epsg()
    return f"EPSG:{epsg}" if epsg else "local transverse Mercator"


def _georeference(ax, geo, e):
    """The grid's CRS coordinates on the bottom and left axes, longitude and latitude on the
    top and right ones, a north arrow."""
    a = geo.world_to_map(np.eye(2)) - geo.world_to_map(np.zeros((1, 2)))
    names = [f"{axis.name.lower()} ({axis.unit_name}, {_crs_name(geo)})"
             for axis in geo.crs.axis_info[:2]]
    if abs(a[0, 1]) < 1e-12 and abs(a[1, 0]) < 1e-12:  # map axes along world x and y
        for k, (make, name) in enumerate(((ax.secondary_xaxis, names[0]),
                                          (ax.secondary_yaxis, names[1]))):
            scale, shift = a[k, k], float(geo.world_to_map(np.zeros((1, 2)))[0, k])
            sec = make("bottom" if k == 0 else "left",
                       functions=(lambda v, s=scale, c=shift: s * np.asarray(v) + c,
                                  lambda v, s=scale, c=shift: (np.asarray(v) - c) / s))
            sec.set_xlabel(name) if k == 0 else sec.set_ylabel(name)
            sec.ticklabel_format(useOffset=False, style="plain")
        ax.tick_params(bottom=False, left=False, labelbottom=False, labelleft=False)
    else:
        ax.set_xlabel("x (m, grid frame)")
        ax.set_ylabel("y (m, grid frame)")
    from matplotlib.ticker import MaxNLocator

    for k, (edge, side) in enumerate(((e[3], "top"), (e[1], "right"))):
        t = np.linspace(e[0], e[1], 400) if k == 0 else np.linspace(e[2], e[3], 400)
        xy = (np.column_stack([t, np.full_like(t, edge)]) if k == 0 else
              np.column_stack([np.full_like(t, edge), t]))
        value = geo.to_lonlat(xy)[:, k]  # longitude along the top, latitude along the right
        order = np.argsort(value)
        ticks = [v for v in MaxNLocator(4).tick_values(value.min(), value.max())
                 if value.min() <= v <= value.max()]
        where = np.interp(ticks, value[order], t[order])
        hemi = ("E", "W") if k == 0 else ("N", "S")
        labels = [f"{abs(v):.{_decimals(ticks)}f}°{hemi[int(v < 0)]}" for v in ticks]
        sec = ax.secondary_xaxis("top") if k == 0 else ax.secondary_yaxis("right")
        (sec.set_xticks if k == 0 else sec.set_yticks)(where, labels=labels)
        sec.tick_params(labelsize=7)
    centre = np.array([[0.5 * (e[0] + e[1]), 0.5 * (e[2] + e[3])]])
    azimuth = float(geo.grid_north_azimuth(centre)[0])  # of world +y, clockwise from north
    north = np.array([-np.sin(azimuth), np.cos(azimuth)])
    size = 0.08 * min(e[1] - e[0], e[3] - e[2])
    base = np.array([e[1] - 1.6 * size, e[2] + 0.6 * size])
    ax.annotate("", xy=base + size * north, xytext=base,
                arrowprops={"arrowstyle": "-|>", "color": "k", "lw": 1.2})
    ax.text(*(base + 1.35 * size * north), "N", ha="center", va="center", fontsize=9,
            fontweight="bold")


def _decimals(ticks) -> int:
    """The fewest decimals that write every tick exactly (at most 6, ~0.1 m)."""
    return next((d for d in range(7) if np.allclose(np.round(ticks, d), ticks, rtol=0,
                                                     atol=1e-9)), 6)


def _figsize(bathy, width=7.0):
    e = _extent(bathy)
    aspect = (e[3] - e[2]) / max(e[1] - e[0], 1e-9)
    return (width, float(np.clip(width * aspect * 0.85, 3.0, 12.0)))


def _classification_image(ax, plan, alpha=1.0):
    labels = plan.labels
    img = np.where(labels.valid, np.where(labels.high, 2, 1), 0)
    cmap = ListedColormap(["white", "#d9e8f5", "#f4b6a6"])
    ax.imshow(img, origin="lower", extent=_extent(plan.bathy), cmap=cmap, vmin=0, vmax=2,
              interpolation="nearest", alpha=alpha)


def label_runs(points, labels, dims: int = 2,
               max_vertices: int | None = None) -> dict[str, np.ndarray]:
    """Per label, its segments (a segment takes its end sample's label) as one polyline of the
    first `dims` coordinates of `points` (N, 3), a NaN row between runs: one artist per label,
    which Agg simplifies and mplot3d projects in one pass (not an artist or a masked array per
    segment). With `max_vertices`, a path of more samples is drawn through every k-th sample
    of each run (k the fewest that keeps the whole path within it) and the run's last: at
    `DRAWN_VERTICES`, vertices a few pixels apart on a figure of a 4 M-sample site."""
    pts = points[:, :dims]
    lab = labels[1:]
    stride = 1 if max_vertices is None else max(1, -(-len(pts) // max_vertices))
    out = {}
    for name in dict.fromkeys(lab.tolist()):
        edge = np.diff(np.concatenate([[0], (lab == name).astype(np.int8), [0]]))
        start, end = np.flatnonzero(edge == 1), np.flatnonzero(edge == -1)  # segments [s, e)
        count = end - start + 2  # the run's samples s..e and the NaN row after them
        run = np.repeat(np.arange(len(start)), count)
        pos = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
        if stride > 1:  # every stride-th sample, the run's last and its NaN row
            keep = (pos % stride == 0) | (pos >= count[run] - 2)
            run, pos = run[keep], pos[keep]
        line = pts[np.minimum(start[run] + pos, len(pts) - 1)]
        line[pos == count[run] - 1] = np.nan
        out[name] = line[:-1]
    return out


def _path_lines(ax, path, colours=LABEL_COLOURS, widths=None, skip=()):
    """The path's segments in plan view, one line per label but those of `skip`."""
    for name, line in label_runs(path.points, path.labels, 2, DRAWN_VERTICES).items():
        if name in skip:
            continue
        ax.plot(line[:, 0], line[:, 1], color=colours.get(name, "k"),
                lw=(widths or {}).get(name, 0.6), label=name, scalex=False, scaley=False)


def fig_slope(plan, geo=None) -> Figure:
    fig = Figure(figsize=_figsize(plan.bathy))
    ax = _plan_axes(fig, plan.bathy, "Slope map S = |grad z|", geo)
    im = ax.imshow(plan.labels.slope, origin="lower", extent=_extent(plan.bathy), cmap="viridis")
    fig.colorbar(im, ax=ax, label="slope (rise / run)")
    return fig


def fig_classification(plan, geo=None) -> Figure:
    fig = Figure(figsize=_figsize(plan.bathy))
    ax = _plan_axes(fig, plan.bathy, f"Classification: {plan.labels.n_regions} high-slope "
                    f"region(s), delta_s = {plan.parameters.slope_threshold}", geo)
    _classification_image(ax, plan)
    return fig


def fig_cells(plan, geo=None) -> Figure:
    fig = Figure(figsize=_figsize(plan.bathy))
    ax = _plan_axes(fig, plan.bathy, f"Boustrophedon cells ({len(plan.cells.cells)}) and "
                    "adjacency graph", geo)
    _classification_image(ax, plan, alpha=0.5)
    frame = plan.cells.frame
    centres = [c.centroid(frame) for c in plan.cells.cells]
    for k, cell in enumerate(plan.cells.cells):
        poly = cell.outline(frame)
        ax.plot(poly[:, 0], poly[:, 1], lw=0.8, color=f"C{k % 10}")
        ax.text(*centres[k], str(k), ha="center", va="center", fontsize=7)
    for i, j in plan.cells.edges:
        ax.plot([centres[i][0], centres[j][0]], [centres[i][1], centres[j][1]], "k--", lw=0.7)
    if centres:
        c = np.array(centres)
        ax.plot(c[:, 0], c[:, 1], "ko", ms=3)
    return fig


def fig_lanes(plan, geo=None) -> Figure:
    fig = Figure(figsize=_figsize(plan.bathy))
    ax = _plan_axes(fig, plan.bathy, f"Lanes in each cell, spacing "
                    f"{plan.lane_spacing:.2f} m", geo)
    _classification_image(ax, plan, alpha=0.5)
    _path_lines(ax, plan.path, colours={"planar": "tab:blue", "transit": "0.6"},
                skip=("slice",))  # the segments flown, without the slices' (contours.png)
    ax.legend(loc="upper right", fontsize=7)
    return fig


def fig_contours(plan, geo=None) -> Figure:
    fig = Figure(figsize=_figsize(plan.bathy))
    ax = _plan_axes(fig, plan.bathy, f"Slicing contours ({len(plan.contours)} pieces)", geo)
    _classification_image(ax, plan, alpha=0.5)
    if plan.contours:
        levels = np.array([c.level for c in plan.contours])
        norm = (levels - levels.min()) / max(np.ptp(levels), 1e-9)
        segs = [c.surface[:, :2] for c in plan.contours]
        from matplotlib import colormaps

        ax.add_collection(LineCollection(segs, colors=colormaps["plasma"](norm), linewidths=0.7))
    return fig


def fig_path3d(plan, which: str = "path") -> Figure:
    path = plan.path if which == "path" else plan.lawnmower
    fig = Figure(figsize=(8, 6))
    ax = fig.add_subplot(1, 1, 1, projection="3d")
    b = plan.bathy
    step = max(1, int(max(b.shape) / 120))
    xx, yy = np.meshgrid(b.x[::step], b.y[::step])
    ax.plot_surface(xx, yy, plan.surface.z[::step, ::step], cmap="gist_earth", alpha=0.5,
                    linewidth=0, antialiased=False)
    for name, line in label_runs(path.points, path.labels, 3, DRAWN_VERTICES).items():
        ax.plot(line[:, 0], line[:, 1], line[:, 2], color=LABEL_COLOURS.get(name, "k"),
                lw=1.6 if name == "slice" else 0.6, label=name)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    title = "Combined 3D coverage path" if which == "path" else "Standard lawnmower path"
    ax.set_title(f"{title}: {path.length:.0f} m")
    ax.legend(loc="upper left", fontsize=7)
    return fig


PLAN_VIEWS = {
    "slope.png": fig_slope,
    "classification.png": fig_classification,
    "cells.png": fig_cells,
    "lanes.png": fig_lanes,
    "contours.png": fig_contours,
}
VIEWS_3D = {
    "path3d.png": lambda plan: fig_path3d(plan, "path"),
    "lawnmower.png": lambda plan: fig_path3d(plan, "lawnmower"),
}


def write_figures(plan, outdir, dpi: int = 110, progress=False,
                  geo=None) -> list[Path]:
    """Writes every figure of `PLAN_VIEWS` (in `geo`'s CRS, with latitude, longitude and
    north, when given) and `VIEWS_3D` into `outdir`; returns the files. `progress`: show the
    progress over the figures, or a caller's `RunProgress` to advance by one per figure."""
    from drake_auv.progress import phase_display

    outdir = Path(outdir)
    written = []
    makers = {**{k: (lambda plan, f=f: f(plan, geo)) for k, f in PLAN_VIEWS.items()}, **VIEWS_3D}
    with phase_display(progress, "figures", len(makers)) as display:
        for name, make in makers.items():
            with display.step(name):
                fig = make(plan)
                with replacing(outdir / name) as temporary:
                    fig.savefig(temporary, dpi=dpi, bbox_inches="tight")
                written.append(outdir / name)
    return written
