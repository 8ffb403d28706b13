"""The report's figures: coverage of the target by viewing angle, coverage against time, and
the true distance and clearance by phase with the tracks from above."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from drake_auv.geometry.visibility import coverage_share
from drake_auv.mission.report.summary import COVERAGE_LEVELS, near_distance
from drake_auv.mission.runner import VEHICLE_RADIUS, MissionResult
from drake_auv.signals import VehicleState


PHASE_COLOURS = {"transit": "0.45", "follow": "tab:green", "survey": "tab:blue"}


def fig_coverage(result: MissionResult) -> Figure:
    """The target's faces coloured by the best multibeam viewing angle of the dive."""
    from matplotlib import colormaps
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    best = result.coverage.multibeam_best
    triangles = np.asarray(result.site.world.triangles)[result.site.target_faces]
    colours = colormaps["viridis_r"](np.clip(np.degrees(np.nan_to_num(best, nan=0.0)) / 90.0,
                                             0.0, 1.0))
    colours[~np.isfinite(best)] = (0.85, 0.1, 0.1, 1.0)
    fig = Figure(figsize=(11, 5))
    lo, hi = triangles.reshape(-1, 3).min(axis=0), triangles.reshape(-1, 3).max(axis=0)
    for k, (elev, azim) in enumerate(((25, -60), (-15, 120))):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        ax.add_collection3d(Poly3DCollection(triangles, facecolors=colours, linewidths=0))
        ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]),
               xlabel="x (m)", ylabel="y (m)", zlabel="z (m)")
        ax.set_box_aspect(np.maximum(hi - lo, 1e-3))
        ax.view_init(elev=elev, azim=azim)
    share = coverage_share(best, result.coverage.areas)
    fig.suptitle(f"Multibeam coverage of the target: {100 * share:.1f} % "
                 "(colour: best viewing angle, 0 (yellow) to 90 deg (purple); red: unseen)")
    return fig


def fig_coverage_vs_time(result: MissionResult, curve: dict) -> Figure:
    """Multibeam and camera coverage of the true target against mission time (`curve`, the
    report's `coverage_vs_time`), over the phases of the dive."""
    fig = Figure(figsize=(8, 4))
    ax = fig.add_subplot(1, 1, 1)
    for phase in result.dive.phases:
        ax.axvspan(phase.start_s, phase.end_s, color=PHASE_COLOURS.get(phase.name, "0.8"),
                   alpha=0.08, lw=0)
    t = np.asarray(curve["t_s"])
    ax.plot(t, 100 * np.asarray(curve["multibeam"]), color="tab:blue", label="multibeam")
    ax.plot(t, 100 * np.asarray(curve["camera"]), color="tab:orange", label="camera")
    for level in COVERAGE_LEVELS:
        ax.axhline(100 * level, color="0.6", lw=0.6, ls="--")
    ax.set(xlabel="mission time (s)", ylabel="coverage of the true target (%)", ylim=(0, 101),
           xlim=(0, t[-1]), title="Coverage against time (shading: phases)")
    ax.legend(loc="lower right", fontsize=8)
    return fig


def fig_distance(result: MissionResult) -> Figure:
    """True distance to the target and clearance against time, by phase; tracks from above."""
    fig = Figure(figsize=(13, 5))
    ax, top = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    names = np.array([result.plan.legs[leg].phase for leg in result.log.leg_at])
    state = VehicleState(result.log.state)
    for name in dict.fromkeys(names):
        mask = names == name
        colour = PHASE_COLOURS.get(name, "k")
        t = np.where(mask, result.log.times, np.nan)
        ax.plot(t, np.where(mask, result.log.distance, np.nan), color=colour, lw=0.9,
                label=f"{name}: distance to the target")
        ax.plot(t, np.where(mask, result.log.clearance, np.nan), color=colour, lw=0.6, ls=":")
        top.plot(np.where(mask, state.x, np.nan), np.where(mask, state.y, np.nan),
                 color=colour, lw=0.8, label=name)
    band = near_distance(result) / 2.0
    if np.isfinite(band):  # a mission that only flies an exported file knows no Omega
        ax.axhline(band, color="k", ls="--", lw=0.8, label=f"Omega = {band:g} m")
    else:
        band = float(np.nanmax(result.log.distance)) / 3.0
    ax.axhline(VEHICLE_RADIUS, color="tab:red", lw=0.8, label="vehicle radius (contact)")
    ax.set(xlabel="mission time (s)", ylabel="m", ylim=(0, 3 * band),
           title="True distance (solid) and clearance to anything (dotted)")
    ax.legend(fontsize=7, loc="upper right")
    if result.plan.nominal is not None:
        nominal = result.plan.nominal.points
        top.plot(nominal[:, 0], nominal[:, 1], color="0.5", lw=0.6, ls="--",
                 label="nominal plan (prior map)")
    centres = np.asarray(result.site.world.triangles_center)[result.site.target_faces]
    stride = max(1, len(centres) // 4000)
    top.scatter(centres[::stride, 0], centres[::stride, 1], s=0.5, c=centres[::stride, 2],
                cmap="gist_earth")
    top.set(aspect="equal", xlabel="x (m, local)", ylabel="y (m, local)",
            title="Tracks from above")
    top.legend(fontsize=7, loc="upper right")
    return fig
