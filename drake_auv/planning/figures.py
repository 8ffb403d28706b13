"""PNG figures of a `CoveragePlan`, like the reference's Figures 76 to 80.

Uses `matplotlib.figure.Figure` directly (no pyplot, no display backend needed).
"""

from __future__ import annotations

from pathlib import Path as FilePath

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure

from drake_auv.output_files import replacing

LABEL_COLOURS = {"planar": "tab:blue", "slice": "tab:red", "transit": "0.6", "lawnmower": "tab:green"}


def _extent(bathy):
    dx, dy = bathy.spacing
    xmin, xmax, ymin, ymax = bathy.extent
    return (xmin - dx / 2, xmax + dx / 2, ymin - dy / 2, ymax + dy / 2)


def _plan_axes(fig, bathy, title):
    ax = fig.add_subplot(1, 1, 1)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title)
    e = _extent(bathy)
    ax.set_xlim(e[0], e[1])
    ax.set_ylim(e[2], e[3])
    return ax


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


def _path_lines(ax, path, colours=LABEL_COLOURS, widths=None):
    xy = path.points[:, :2]
    segs = np.stack([xy[:-1], xy[1:]], axis=1)
    lab = path.labels[1:]
    for name in dict.fromkeys(lab.tolist()):
        m = lab == name
        lw = (widths or {}).get(name, 0.6)
        ax.add_collection(LineCollection(segs[m], colors=colours.get(name, "k"), linewidths=lw,
                                         label=name))


def fig_slope(plan) -> Figure:
    fig = Figure(figsize=_figsize(plan.bathy))
    ax = _plan_axes(fig, plan.bathy, "Slope map S = |grad z|")
    im = ax.imshow(plan.labels.slope, origin="lower", extent=_extent(plan.bathy), cmap="viridis")
    fig.colorbar(im, ax=ax, label="slope (rise / run)")
    return fig


def fig_classification(plan) -> Figure:
    fig = Figure(figsize=_figsize(plan.bathy))
    ax = _plan_axes(fig, plan.bathy, f"Classification: {plan.labels.n_regions} high-slope "
                    f"region(s), delta_s = {plan.parameters['slope_threshold']}")
    _classification_image(ax, plan)
    return fig


def fig_cells(plan) -> Figure:
    fig = Figure(figsize=_figsize(plan.bathy))
    ax = _plan_axes(fig, plan.bathy, f"Boustrophedon cells ({len(plan.cells.cells)}) and "
                    "adjacency graph")
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


def fig_lanes(plan) -> Figure:
    fig = Figure(figsize=_figsize(plan.bathy))
    ax = _plan_axes(fig, plan.bathy, f"Lanes in each cell, spacing "
                    f"{plan.parameters['lane_spacing']:.2f} m")
    _classification_image(ax, plan, alpha=0.5)
    _path_lines(ax, plan.path.select(plan.path.labels != "slice"),
                colours={"planar": "tab:blue", "transit": "0.6"})
    ax.legend(loc="upper right", fontsize=7)
    return fig


def fig_contours(plan) -> Figure:
    fig = Figure(figsize=_figsize(plan.bathy))
    ax = _plan_axes(fig, plan.bathy, f"Slicing contours ({len(plan.contours)} pieces)")
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
    pts = path.points
    for name in dict.fromkeys(path.labels.tolist()):
        m = path.labels == name
        seg = np.where(m, pts[:, 2], np.nan)  # break the line where the label changes
        ax.plot(pts[:, 0], pts[:, 1], seg, color=LABEL_COLOURS.get(name, "k"),
                lw=1.6 if name == "slice" else 0.6, label=name)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    title = "Combined 3D coverage path" if which == "path" else "Standard lawnmower path"
    ax.set_title(f"{title}: {path.length:.0f} m")
    ax.legend(loc="upper left", fontsize=7)
    return fig


FIGURES = {
    "slope.png": fig_slope,
    "classification.png": fig_classification,
    "cells.png": fig_cells,
    "lanes.png": fig_lanes,
    "contours.png": fig_contours,
    "path3d.png": lambda plan: fig_path3d(plan, "path"),
    "lawnmower.png": lambda plan: fig_path3d(plan, "lawnmower"),
}


def write_figures(plan, outdir, dpi: int = 110, progress: bool = False) -> list[FilePath]:
    """Writes every figure of `FIGURES` into `outdir`; returns the files."""
    from tqdm import tqdm

    outdir = FilePath(outdir)
    written = []
    for name, make in tqdm(FIGURES.items(), desc="figures", disable=not progress, leave=False):
        fig = make(plan)
        with replacing(outdir / name) as temporary:
            fig.savefig(temporary, dpi=dpi, bbox_inches="tight")
        written.append(outdir / name)
    return written
