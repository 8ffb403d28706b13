"""Report of the boulder mission: tables (Markdown and JSON) and figures.

Numbers in `results` depend only on the configuration and seed (the same seed writes the same
numbers); wall-clock figures (real-time factor, replanning step times) go in `timing`, which
varies with the machine and its load.
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path as FilePath

import numpy as np
from matplotlib.figure import Figure

from drake_auv.geometry.distance import mesh_distance
from drake_auv.geometry.visibility import coverage_share
from drake_auv.mission import VEHICLE_RADIUS, MissionResult, PhaseResult, target_mesh
from drake_auv.planning.figures import fig_path3d

PHASE_TITLES = {"profile": "2. Horizontal profile following",
                "replan": "3. Nominal plan with realtime replanning"}


def angle_stats(best: np.ndarray, areas: np.ndarray) -> tuple[float, float]:
    """Area-weighted mean and standard deviation of the seen faces' best angles, degrees."""
    seen = np.isfinite(best)
    if not seen.any():
        return float("nan"), float("nan")
    w = areas[seen] / areas[seen].sum()
    deg = np.degrees(best[seen])
    mean = float(w @ deg)
    return mean, float(np.sqrt(w @ (deg - mean) ** 2))


def phase_summary(phase: PhaseResult, areas: np.ndarray, near: float) -> dict:
    """Statistics of one simulated phase; distances over the samples within `near` m of the
    structure (lanes far out over the seabed say nothing about the offset)."""
    close = phase.distance < near
    d = phase.distance[close] if close.any() else phase.distance
    cam_mean, cam_sd = angle_stats(phase.camera_best, areas)
    mb_mean, mb_sd = angle_stats(phase.multibeam_best, areas)
    return dict(length_m=phase.length, duration_s=phase.duration,
                distance_mean_m=float(d.mean()), distance_sd_m=float(d.std()),
                distance_min_m=float(phase.distance.min()),
                clearance_min_m=float(phase.clearance.min()),
                contact=bool(phase.clearance.min() <= VEHICLE_RADIUS),
                navigation_error_max_m=float(np.linalg.norm(
                    phase.estimated_xyz - phase.xyz, axis=1).max()),
                camera_coverage=coverage_share(phase.camera_best, areas),
                multibeam_coverage=coverage_share(phase.multibeam_best, areas),
                camera_angle_mean_deg=cam_mean, camera_angle_sd_deg=cam_sd,
                multibeam_angle_mean_deg=mb_mean, multibeam_angle_sd_deg=mb_sd)


def plan_summary(result: MissionResult) -> dict:
    """The off-line plan: lengths, planned duration, the planner's own metrics on the prior
    map, and the true distance of the nominal path to the structure (the prior map's error)."""
    plan, config = result.plan, result.config
    path = plan.path
    samples = path.resample(1.0).points
    d = mesh_distance(target_mesh(result.scenario), samples)
    close = d < 2.0 * config.omega
    m = plan.metrics
    return dict(length_m=path.length,
                length_by_label_m=path.length_by_label(),
                planned_duration_s=float(path.times(config.speed)[-1]),
                high_slope_regions=int(plan.labels.n_regions),
                planned_view_mean_deg=m.total.view_mean_deg,
                planned_view_sd_deg=m.total.view_sd_deg,
                planned_coverage_prior=m.total.coverage,
                planned_clearance_min_prior_m=m.total.min_clearance,
                nominal_true_distance_mean_m=float(d[close].mean()),
                nominal_true_distance_min_m=float(d.min()))


def summarise(result: MissionResult) -> dict:
    """Everything the report shows: `results` (deterministic) and `timing` (wall clock)."""
    config, areas = result.config, result.areas
    near = 2.0 * config.omega
    phases = {p.name: phase_summary(p, areas, near) for p in result.phases}
    union = {sensor: np.fmin.reduce([getattr(p, f"{sensor}_best") for p in result.phases])
             for sensor in ("camera", "multibeam")}
    mission = dict(camera_coverage=coverage_share(union["camera"], areas),
                   multibeam_coverage=coverage_share(union["multibeam"], areas),
                   clearance_min_m=min(s["clearance_min_m"] for s in phases.values()),
                   contact=any(s["contact"] for s in phases.values()),
                   target_area_m2=float(areas.sum()))
    timing = {}
    for p in result.phases:
        timing[p.name] = dict(wall_s=p.wall, real_time_factor=p.duration / max(p.wall, 1e-9))
        if len(p.replan_wall):
            timing[p.name].update(replan_steps=len(p.replan_wall),
                                  replan_median_ms=float(np.median(p.replan_wall) * 1e3),
                                  replan_p95_ms=float(np.percentile(p.replan_wall, 95) * 1e3))
    results = dict(plan=plan_summary(result), **phases, mission=mission)
    return dict(config=asdict(config), results=_rounded(results), timing=_rounded(timing))


def _rounded(value, digits: int = 4):
    if isinstance(value, dict):
        return {k: _rounded(v, digits) for k, v in value.items()}
    if isinstance(value, (float, np.floating)):
        return round(float(value), digits)
    return value


def report_markdown(summary: dict) -> str:
    r, t, c = summary["results"], summary["timing"], summary["config"]
    plan = r["plan"]
    lines = [
        "# Boulder mission report",
        "",
        f"Seed {c['seed']}; prior map off by {c['prior_error_m']:g} m; Omega = "
        f"{c['omega']:g} m; {c['slice_count']} contours {c['slice_spacing']:g} m apart; survey "
        f"speed {c['speed']:g} m/s; navigation drift: compass bias {c['heading_bias_deg']:g} "
        f"deg, DVL scale error {100 * c['dvl_scale_error']:g} %, random walk "
        f"{c['random_walk']:g} m/sqrt(m).",
        "",
        "## 1. Off-line plan (on the prior map)",
        "",
        "| quantity | value |",
        "| --- | --- |",
        f"| path length | {plan['length_m']:.1f} m ("
        + ", ".join(f"{k} {v:.1f} m" for k, v in plan["length_by_label_m"].items()) + ") |",
        f"| planned duration | {plan['planned_duration_s']:.0f} s |",
        f"| high-slope regions | {plan['high_slope_regions']} |",
        f"| viewing angle on the prior map | {plan['planned_view_mean_deg']:.1f} deg "
        f"(sd {plan['planned_view_sd_deg']:.1f}) |",
        f"| coverage of the prior map | {100 * plan['planned_coverage_prior']:.1f} % |",
        f"| clearance on the prior map | {plan['planned_clearance_min_prior_m']:.2f} m |",
        f"| true distance of the nominal path to the boulder | mean "
        f"{plan['nominal_true_distance_mean_m']:.2f} m, min "
        f"{plan['nominal_true_distance_min_m']:.2f} m |",
        "",
        "## Simulated phases (true state, true surface)",
        "",
        "| quantity | " + " | ".join(PHASE_TITLES[k] for k in ("profile", "replan")) + " |",
        "| --- | --- | --- |",
    ]
    rows = [("path length (m)", "length_m", "{:.1f}"), ("duration (s)", "duration_s", "{:.0f}"),
            ("true distance to the boulder, mean (m)", "distance_mean_m", "{:.2f}"),
            ("true distance to the boulder, sd (m)", "distance_sd_m", "{:.2f}"),
            ("true distance to the boulder, min (m)", "distance_min_m", "{:.2f}"),
            ("clearance to anything, min (m)", "clearance_min_m", "{:.2f}"),
            ("navigation error, max (m)", "navigation_error_max_m", "{:.2f}"),
            ("camera coverage of the boulder (%)", "camera_coverage", "{:.1%}"),
            ("multibeam coverage of the boulder (%)", "multibeam_coverage", "{:.1%}"),
            ("camera viewing angle, mean (deg)", "camera_angle_mean_deg", "{:.1f}"),
            ("camera viewing angle, sd (deg)", "camera_angle_sd_deg", "{:.1f}"),
            ("multibeam viewing angle, mean (deg)", "multibeam_angle_mean_deg", "{:.1f}"),
            ("multibeam viewing angle, sd (deg)", "multibeam_angle_sd_deg", "{:.1f}")]
    for title, key, fmt in rows:
        cells = [fmt.format(r[k][key]).replace("%", "") for k in ("profile", "replan")]
        lines.append(f"| {title} | " + " | ".join(cells) + " |")
    m = r["mission"]
    replan_t = t["replan"]
    lines += [
        "",
        "Distance statistics use the samples within 2 Omega of the boulder; clearance is the "
        "exact distance from the vehicle's centre to the true mesh (boulder and seabed), and "
        f"contact means a clearance at or below the vehicle's radius ({VEHICLE_RADIUS:g} m).",
        "",
        "## Whole mission",
        "",
        f"- Boulder surface above the seabed: {m['target_area_m2']:.0f} m^2.",
        f"- Covered by the multibeam: **{100 * m['multibeam_coverage']:.1f} %**; by the camera: "
        f"**{100 * m['camera_coverage']:.1f} %** (union of both dives).",
        f"- Minimum clearance: {m['clearance_min_m']:.2f} m: "
        + ("**contact**." if m["contact"] else "no contact."),
        "",
        "## Timing (wall clock: varies with the machine and its load)",
        "",
        f"- Profile following: {t['profile']['wall_s']:.1f} s wall, "
        f"{t['profile']['real_time_factor']:.0f}x real time.",
        f"- Replanning: {replan_t['wall_s']:.1f} s wall, "
        f"{replan_t['real_time_factor']:.0f}x real time; {replan_t.get('replan_steps', 0)} "
        f"replanning steps, median {replan_t.get('replan_median_ms', float('nan')):.1f} ms, "
        f"95th percentile {replan_t.get('replan_p95_ms', float('nan')):.1f} ms.",
        "",
        "Figures: `plan.png` (the off-line plan), `coverage.png` (the boulder coloured by the "
        "best multibeam viewing angle), `distance.png` (true distance and clearance against "
        "time, and the tracks from above); `mission.html` is the Meshcat recording.",
        "",
    ]
    return "\n".join(lines)


def fig_coverage(result: MissionResult) -> Figure:
    """The boulder's faces coloured by the best multibeam viewing angle of the mission."""
    from matplotlib import colormaps
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    best = np.fmin.reduce([p.multibeam_best for p in result.phases])
    world, target = result.scenario.world, result.scenario.target_faces
    triangles = np.asarray(world.triangles)[target]
    cmap = colormaps["viridis_r"]
    colours = cmap(np.clip(np.degrees(np.nan_to_num(best, nan=0.0)) / 90.0, 0.0, 1.0))
    colours[~np.isfinite(best)] = (0.85, 0.1, 0.1, 1.0)
    fig = Figure(figsize=(11, 5))
    for k, (elev, azim) in enumerate(((25, -60), (-15, 120))):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        ax.add_collection3d(Poly3DCollection(triangles, facecolors=colours, linewidths=0))
        lo, hi = triangles.reshape(-1, 3).min(axis=0), triangles.reshape(-1, 3).max(axis=0)
        ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]),
               xlabel="x (m)", ylabel="y (m)", zlabel="z (m)")
        ax.set_box_aspect(hi - lo)
        ax.view_init(elev=elev, azim=azim)
    share = coverage_share(best, result.areas)
    fig.suptitle(f"Multibeam coverage of the boulder: {100 * share:.1f} % "
                 "(colour: best viewing angle, 0 (yellow) to 90 deg (purple); red: unseen)")
    return fig


def fig_distance(result: MissionResult) -> Figure:
    """True distance to the boulder and clearance against mission time; tracks from above."""
    config = result.config
    fig = Figure(figsize=(13, 5))
    ax, top = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    offset = 0.0
    colours = {"profile": "tab:green", "replan": "tab:blue"}
    for p in result.phases:
        t = p.times - p.times[0] + offset
        ax.plot(t, p.distance, color=colours[p.name], lw=0.9,
                label=f"{PHASE_TITLES[p.name][3:]}: distance to the boulder")
        ax.plot(t, p.clearance, color=colours[p.name], lw=0.6, ls=":",
                label="clearance to anything")
        top.plot(p.xyz[:, 0], p.xyz[:, 1], color=colours[p.name], lw=0.8,
                 label=PHASE_TITLES[p.name][3:])
        offset = t[-1]
    ax.axhline(config.omega, color="k", ls="--", lw=0.8, label=f"Omega = {config.omega:g} m")
    ax.axhline(config.follow_offset, color="tab:green", ls="--", lw=0.8,
               label=f"following offset {config.follow_offset:g} m")
    ax.axhline(VEHICLE_RADIUS, color="tab:red", lw=0.8, label="vehicle radius")
    ax.set(xlabel="mission time (s)", ylabel="m", ylim=(0, 3 * config.omega),
           title="True distance against time")
    ax.legend(fontsize=7, loc="upper right")
    nominal = result.plan.path.points
    top.plot(nominal[:, 0], nominal[:, 1], color="0.5", lw=0.6, ls="--",
             label="nominal plan (prior map)")
    world = result.scenario.world
    centres = np.asarray(world.triangles_center)[result.scenario.target_faces]
    top.scatter(centres[::7, 0], centres[::7, 1], s=0.5, c=centres[::7, 2], cmap="gist_earth")
    top.set(aspect="equal", xlabel="x (m)", ylabel="y (m)", title="Tracks from above")
    top.legend(fontsize=7, loc="upper right")
    return fig


def write_report(result: MissionResult, outdir, dpi: int = 110) -> dict:
    """Writes report.md, report.json, plan.png, coverage.png and distance.png; returns the
    summary."""
    out = FilePath(outdir)
    out.mkdir(parents=True, exist_ok=True)
    summary = summarise(result)
    (out / "report.json").write_text(json.dumps(summary, indent=2) + "\n")
    (out / "report.md").write_text(report_markdown(summary))
    figures = {"plan.png": fig_path3d(result.plan), "coverage.png": fig_coverage(result),
               "distance.png": fig_distance(result)}
    for name, fig in figures.items():
        fig.savefig(out / name, dpi=dpi, bbox_inches="tight")
    return summary
