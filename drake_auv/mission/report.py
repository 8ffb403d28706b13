"""The report of a flown mission: `report.json`, `report.md`, figures, the trajectory and the
Diagram, written by `write_outputs`.

`report.json` keys (a contract; more may be added): `coverage.multibeam`, `coverage.camera`
(fractions of the target's area, union over the dive), `min_clearance_m` (the true signed
clearance to anything, `geometry.clearance`: negative inside the world or above the sea
surface), `contact` (that clearance at or below the vehicle's radius), `distance_to_target`
(`mean_m`, `sd_m`, `min_m` over the survey samples within 2 Omega of the target, and `map_mean_m`, the same against the on-line map's voxels on the
target, as the reference reports it), `phases` (`name`, `start_s`, `end_s`, one time axis),
`faults` (the injected ones, as in the mission file), `responses` (the supervisor's answers:
`response`, `cause`, `start_s`, `end_s`), `mission.aborted` and `coverage_vs_time` (`t_s`,
`multibeam`, `camera`: the covered shares every `period_s` from 0 to the end of the dive, and
`time_to_s`, the exact mission time each sensor first covered 80 % and 90 %, null if never).
Everything but `timing` depends only on the mission file and its seed. `timing` (wall clock,
s): `sim_s` simulated; `wall_s` = `simulation_s`, the simulation's wall time, and
`real_time_factor` = `sim_s / simulation_s`; from `write_outputs`, the end-to-end figures:
`setup_s` (when the caller measured it: loading, planning, building the Diagram, reading the
logs back), `outputs_s` (every file, the Meshcat recording included), `reconstruction_s` (of
which the point cloud and the surface), `total_s` and `peak_rss_mb` (the process's peak
resident memory, MiB).
"""

from __future__ import annotations

import csv
import dataclasses
import resource
import time
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from drake_auv.geometry.distance import mesh_distance
from drake_auv.geometry.visibility import coverage_share
from drake_auv.exploration.view_planner import exploration_summary
from drake_auv.mapping.mapper import map_memory
from drake_auv.mission.config import mission_to_dict
from drake_auv.mission.ocean_summary import ocean_markdown, ocean_summary
from drake_auv.mission.runner import VEHICLE_RADIUS, MissionResult
from drake_auv.output_files import open_replacing, replacing, write_json, write_text
from drake_auv.planning.figures import fig_path3d
from drake_auv.progress import RunProgress
from drake_auv.reconstruction.products import (SURFACE_STAGES, products_markdown,
                                               write_products)
from drake_auv.signals import ReplanningStep, VehicleState, Water

PHASE_COLOURS = {"transit": "0.45", "follow": "tab:green", "survey": "tab:blue"}
COVERAGE_PERIOD_S = 10.0  # s, the sampling of the coverage-against-time curve
COVERAGE_LEVELS = (0.8, 0.9)  # the shares whose first time the report gives


def angle_stats(best: np.ndarray, areas: np.ndarray) -> tuple[float, float]:
    """Area-weighted mean and standard deviation of the seen faces' best angles, degrees."""
    seen = np.isfinite(best)
    if not seen.any():
        return float("nan"), float("nan")
    w = areas[seen] / areas[seen].sum()
    deg = np.degrees(best[seen])
    mean = float(w @ deg)
    return mean, float(np.sqrt(w @ (deg - mean) ** 2))


def near_distance(result: MissionResult) -> float:
    """The band (m) within which survey samples count for the distance statistics: 2 Omega
    (2 x the largest following offset without a plan; every sample when neither is known, as
    for a mission that only flies an exported file)."""
    if result.plan.omega is not None:
        return 2.0 * result.plan.omega
    if not result.plan.legs_of("follow"):
        return float("inf")
    return 2.0 * max(step.params.offset for step in result.plan.legs_of("follow").values())


def _scored_samples(result: MissionResult) -> np.ndarray:
    """Mask of the samples the distance statistics use: survey legs (follow legs without a
    survey), within 2 Omega of the target."""
    names = np.array([result.plan.legs[leg].phase for leg in result.leg_at])
    scored = names == ("survey" if (names == "survey").any() else "follow")
    near = scored & (result.distance < near_distance(result))
    return near if near.any() else scored


def map_distance(result: MissionResult, samples: np.ndarray) -> np.ndarray:
    """Distance from `samples` (n, 3) to the on-line map's occupied voxels lying on the
    target (within 1.5 voxels of its true surface), m; inf without any."""
    from scipy.spatial import cKDTree

    voxels = result.online_map.map.occupied_points()
    if len(voxels) == 0 or len(samples) == 0:
        return np.full(len(samples), np.inf)
    on_target = mesh_distance(result.site.target_mesh, voxels) <= 1.5 * result.online_map.map.resolution
    if not on_target.any():
        return np.full(len(samples), np.inf)
    return cKDTree(voxels[on_target]).query(samples)[0]


def phase_summary(result: MissionResult, mask: np.ndarray) -> dict:
    """Statistics of the samples `mask` of the dive."""
    t, xyz = result.times[mask], VehicleState(result.state[mask]).position
    nav_error = np.linalg.norm(VehicleState(result.estimated[mask]).position - xyz, axis=1)
    return dict(length_m=float(np.linalg.norm(np.diff(xyz, axis=0), axis=1).sum()),
                duration_s=float(t[-1] - t[0]) if len(t) else 0.0,
                distance_min_m=float(result.distance[mask].min()),
                clearance_min_m=float(result.clearance[mask].min()),
                navigation_error_max_m=float(nav_error.max()))


def plan_summary(result: MissionResult) -> dict | None:
    """The off-line plan: lengths, planned duration, the planner's own metrics on the prior map
    (coverage plans), and the true distance of the nominal path to the target."""
    nominal = result.plan.nominal
    if nominal is None:
        return None
    d = mesh_distance(result.site.target_mesh, nominal.resample(1.0).points)
    close = d < near_distance(result)
    out = dict(length_m=nominal.length, length_by_label_m=nominal.length_by_label(),
               planned_duration_s=float(nominal.times(result.plan.survey_speed)[-1]),
               omega_m=result.plan.omega,
               nominal_true_distance_mean_m=float(d[close].mean()) if close.any() else None,
               nominal_true_distance_min_m=float(d.min()))
    coverage = result.plan.coverage
    if coverage is not None and coverage.metrics is not None:
        m = coverage.metrics.total
        out.update(high_slope_regions=int(coverage.labels.n_regions),
                   planned_view_mean_deg=m.view_mean_deg, planned_view_sd_deg=m.view_sd_deg,
                   planned_coverage_prior=m.coverage,
                   planned_clearance_min_prior_m=m.min_clearance)
    return out


def coverage_curve(first_seen: np.ndarray, areas: np.ndarray, end_s: float,
                   period_s: float = COVERAGE_PERIOD_S) -> tuple[np.ndarray, np.ndarray]:
    """The seen share of the area against mission time from each face's first-seen time (s,
    NaN unseen): (t (k,) s, every `period_s` from 0 and at `end_s`; share (k,) in [0, 1]).
    Its length is bounded by `end_s / period_s`, not by the number of steps."""
    if not (np.isfinite(period_s) and period_s > 0):
        raise ValueError(f"period_s must be > 0 s, got {period_s}")
    t = np.r_[np.arange(0.0, end_s, period_s), end_s]
    times, cumulative = _first_seen_sorted(first_seen, areas)
    return t, cumulative[np.searchsorted(times, t, side="right")]


def time_to_coverage(first_seen: np.ndarray, areas: np.ndarray, level: float) -> float | None:
    """The first mission time (s) the seen share of the area reached `level` in (0, 1], from
    each face's first-seen time; None if it never did."""
    if not (0 < level <= 1):
        raise ValueError(f"level must be in (0, 1], got {level}")
    times, cumulative = _first_seen_sorted(first_seen, areas)
    k = int(np.searchsorted(cumulative[1:], level * (1 - 1e-12), side="left"))
    return float(times[k]) if k < len(times) else None


def _first_seen_sorted(first_seen, areas) -> tuple[np.ndarray, np.ndarray]:
    """The seen faces' first-seen times in order (k,) and the covered share before the first
    and after each (k + 1,)."""
    seen = np.isfinite(first_seen)
    order = np.argsort(first_seen[seen], kind="stable")
    share = np.r_[0.0, np.cumsum(areas[seen][order])] / areas.sum()
    return first_seen[seen][order], share


def coverage_vs_time(result: MissionResult, period_s: float = COVERAGE_PERIOD_S) -> dict:
    """Multibeam and camera coverage of the true target against mission time, from the
    recorders' first-seen state at the end of the dive (`report.json`'s `coverage_vs_time`)."""
    end = float(result.context.get_time())
    out = dict(period_s=period_s, time_to_s={})
    for name in ("multibeam", "camera"):
        recorder = getattr(result.handles, f"{name}_coverage")
        first = recorder.first_seen(recorder.GetMyContextFromRoot(result.context))
        t, out[name] = coverage_curve(first, result.areas, end, period_s)
        out["t_s"] = t
        out["time_to_s"][name] = {f"{100 * level:g}": time_to_coverage(first, result.areas, level)
                                  for level in COVERAGE_LEVELS}
    return {k: v.tolist() if isinstance(v, np.ndarray) else v for k, v in out.items()}


def summarise(result: MissionResult) -> dict:
    """Everything the report shows; `timing` holds the wall-clock figures (they vary with the
    machine), the rest depends only on the mission file and its seed."""
    areas = result.areas
    scored = _scored_samples(result)
    d = result.distance[scored]
    map_d = map_distance(result, VehicleState(result.state[scored]).position)
    map_d = map_d[np.isfinite(map_d)]
    phases = []
    for phase in result.phases:
        mask = np.isin(result.leg_at, phase.legs)
        entry = dict(name=phase.name, start_s=phase.start_s, end_s=phase.end_s,
                     legs=phase.legs, outcomes=[result.outcomes[k] for k in phase.legs])
        if mask.any():
            entry.update(phase_summary(result, mask))
        phases.append(entry)
    cam_mean, cam_sd = angle_stats(result.camera_best, areas)
    mb_mean, mb_sd = angle_stats(result.multibeam_best, areas)
    min_clearance = float(result.clearance.min())
    summary = dict(
        mission=dict(name=result.spec.name, seed=result.spec.seed,
                     site=result.site.name, completed=result.completed,
                     aborted="aborted" in result.outcomes,
                     target_area_m2=float(areas.sum())),
        coverage=dict(multibeam=coverage_share(result.multibeam_best, areas),
                      camera=coverage_share(result.camera_best, areas),
                      multibeam_angle_mean_deg=mb_mean, multibeam_angle_sd_deg=mb_sd,
                      camera_angle_mean_deg=cam_mean, camera_angle_sd_deg=cam_sd),
        min_clearance_m=min_clearance,
        contact=bool(min_clearance <= VEHICLE_RADIUS),
        distance_to_target=dict(
            mean_m=float(d.mean()) if len(d) else None, sd_m=float(d.std()) if len(d) else None,
            min_m=float(result.distance.min()),
            map_mean_m=float(map_d.mean()) if len(map_d) else None,
            map_sd_m=float(map_d.std()) if len(map_d) else None,
            near_m=near_distance(result) if np.isfinite(near_distance(result)) else None,
            samples=int(scored.sum())),
        navigation_error_max_m=float(np.linalg.norm(
            VehicleState(result.estimated).position - VehicleState(result.state).position,
            axis=1).max()),
        phases=phases,
        faults={name: dataclasses.asdict(f) for name, f in result.spec.faults.active.items()},
        responses=result.responses,
        plan=plan_summary(result),
        config=mission_to_dict(result.spec),
        coverage_vs_time=coverage_vs_time(result),
    )
    timing = dict(wall_s=result.wall_s, sim_s=result.duration_s, simulation_s=result.wall_s,
                  real_time_factor=result.duration_s / max(result.wall_s, 1e-9))
    if len(result.replanning):
        wall = ReplanningStep(result.replanning).wall_time
        timing.update(replan_steps=len(wall), replan_median_ms=float(np.median(wall) * 1e3),
                      replan_p95_ms=float(np.percentile(wall, 95) * 1e3))
    summary["timing"] = timing
    summary["map"] = map_memory(result.online_map, result.scan_log)
    ocean = ocean_summary(result)
    if ocean is not None:
        summary["ocean"] = ocean
    if result.handles is not None and result.handles.explorer is not None:
        summary["exploration"] = exploration_summary(result.handles, result.context,
                                                     result.outcomes)
    return _rounded(summary)


def _rounded(value, digits: int = 4):
    if isinstance(value, dict):
        return {k: _rounded(v, digits) for k, v in value.items()}
    if isinstance(value, list):
        return [_rounded(v, digits) for v in value]
    if isinstance(value, (float, np.floating)):
        return round(float(value), digits) if np.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    return value


def _fmt(value, spec: str, unit: str = "") -> str:
    """A table cell: "-" where the quantity does not apply."""
    return "-" if value is None else f"{value:{spec}}{unit}"


FILE_NOTES = {"plan.png": "the coverage plan", "mission.html": "Meshcat recording"}


def _angle(mean, sd) -> str:
    return "" if mean is None else f" (viewing angle {mean:.1f} deg, sd {sd:.1f})"


def _distance_line(d: dict) -> str:
    """The true (and on-line map) distance to the target; the survey's only where it had
    samples."""
    near = "" if d["near_m"] is None else f" within {d['near_m']:g} m"
    parts = [] if d["mean_m"] is None else [
        f"over {d['samples']} survey samples{near}: mean {d['mean_m']:.2f} m, sd "
        f"{d['sd_m']:.2f} m"]
    line = "- True distance to the target: " + "; ".join(
        parts + [f"minimum over the dive {d['min_m']:.2f} m"]) + "."
    if d["map_mean_m"] is not None:
        line += f" Against the on-line map: mean {d['map_mean_m']:.2f} m, sd {d['map_sd_m']:.2f} m."
    return line


def exploration_markdown(section: dict | None) -> list[str]:
    """The report's line on an exploration (`exploration_summary`); none without one."""
    if section is None:
        return []
    stopped = ("nothing more worth seeing" if section["stopped"] == "gain"
               else "its time ran out")
    return [f"- Exploration (next views by {section['strategy']}): "
            f"{section['viewpoints']} viewpoints; the planner believed "
            f"{100 * section['believed_coverage']:.1f} % of the mapped surface covered when "
            f"it stopped ({stopped})."]


def report_markdown(summary: dict, files=()) -> str:
    """The report as Markdown; `files`: the names of the files written beside it, listed at the
    end. Quantities that do not apply (no survey sample, nothing seen) are left out."""
    m, c, d = summary["mission"], summary["coverage"], summary["distance_to_target"]
    lines = [f"# Mission report: {m['name']}", "",
             f"Site `{m['site']}`, seed {m['seed']}; "
             + ("every leg flown." if m["completed"] else "**stopped by the time cap**.")
             + " One dive: the vehicle, its navigation error and the on-line map carry "
             "across the phases.", ""]
    plan = summary["plan"]
    if plan is not None:
        lines += ["## Off-line plan (on the prior map)", "", "| quantity | value |",
                  "| --- | --- |",
                  f"| path length | {plan['length_m']:.1f} m ("
                  + ", ".join(f"{k} {v:.1f} m" for k, v in plan["length_by_label_m"].items())
                  + ") |",
                  f"| planned duration | {plan['planned_duration_s']:.0f} s |",
                  f"| Omega | {plan['omega_m']:g} m |",
                  "| true distance of the nominal path to the target | "
                  + ("" if plan["nominal_true_distance_mean_m"] is None else
                     f"mean {plan['nominal_true_distance_mean_m']:.2f} m, ")
                  + f"min {plan['nominal_true_distance_min_m']:.2f} m |"]
        if "planned_coverage_prior" in plan:
            lines += [f"| high-slope regions | {plan['high_slope_regions']} |",
                      f"| viewing angle on the prior map | {plan['planned_view_mean_deg']:.1f}"
                      f" deg (sd {plan['planned_view_sd_deg']:.1f}) |",
                      f"| coverage of the prior map | "
                      f"{100 * plan['planned_coverage_prior']:.1f} % |"]
        lines.append("")
    lines += ["## Phases (true state, true surface)", "",
              "| phase | start (s) | end (s) | length (m) | min distance to target (m) | "
              "min clearance (m) | max navigation error (m) | legs |",
              "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for p in summary["phases"]:
        lines.append(f"| {p['name']} | {p['start_s']:.0f} | {p['end_s']:.0f} | "
                     f"{_fmt(p.get('length_m'), '.1f')} | {_fmt(p.get('distance_min_m'), '.2f')}"
                     f" | {_fmt(p.get('clearance_min_m'), '.2f')} | "
                     f"{_fmt(p.get('navigation_error_max_m'), '.2f')} | "
                     + ", ".join(f"{k} ({o})" for k, o in zip(p["legs"], p["outcomes"])) + " |")
    lines += ["", "## Whole dive", "",
              f"- Target surface: {m['target_area_m2']:.0f} m^2. Covered by the multibeam: "
              f"**{100 * c['multibeam']:.1f} %**"
              f"{_angle(c['multibeam_angle_mean_deg'], c['multibeam_angle_sd_deg'])}; by the "
              f"camera: **{100 * c['camera']:.1f} %**"
              f"{_angle(c['camera_angle_mean_deg'], c['camera_angle_sd_deg'])}.",
              _distance_line(d),
              coverage_time_line(summary["coverage_vs_time"]),
              f"- Minimum signed clearance to anything (negative: inside the world or out "
              f"of the water): {summary['min_clearance_m']:.2f} m: "
              + ("**contact**." if summary["contact"] else "no contact.")
              + f" Largest navigation error: {summary['navigation_error_max_m']:.2f} m.",
              *exploration_markdown(summary.get("exploration")),
              *ocean_markdown(summary.get("ocean")),
              "", "## Timing (wall clock: varies with the machine and its load)", ""]
    t = summary["timing"]
    lines.append(f"- {t['sim_s']:.0f} s simulated in {t['wall_s']:.1f} s wall: "
                 f"{t['real_time_factor']:.0f}x real time.")
    if "outputs_s" in t:
        setup = "" if t.get("setup_s") is None else f"setup {t['setup_s']:.1f} s, "
        lines.append(f"- End to end {t['total_s']:.1f} s: {setup}simulation "
                     f"{t['simulation_s']:.1f} s, outputs {t['outputs_s']:.1f} s (of which the "
                     f"reconstruction {t['reconstruction_s']:.1f} s); peak memory "
                     f"{t['peak_rss_mb']:.0f} MiB.")
    if "replan_steps" in t:
        lines.append(f"- {t['replan_steps']} replanning steps: median "
                     f"{t['replan_median_ms']:.1f} ms, 95th percentile {t['replan_p95_ms']:.1f}"
                     " ms.")
    if files:
        lines += ["", "Files: " + ", ".join(
            f"`{name}`" + (f" ({FILE_NOTES[name]})" if name in FILE_NOTES else "")
            for name in files) + "."]
    return "\n".join(lines) + "\n"


def fig_coverage(result: MissionResult) -> Figure:
    """The target's faces coloured by the best multibeam viewing angle of the dive."""
    from matplotlib import colormaps
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    best = result.multibeam_best
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
    share = coverage_share(best, result.areas)
    fig.suptitle(f"Multibeam coverage of the target: {100 * share:.1f} % "
                 "(colour: best viewing angle, 0 (yellow) to 90 deg (purple); red: unseen)")
    return fig


def coverage_time_line(curve: dict) -> str:
    """The report's line on when each sensor reached the `COVERAGE_LEVELS`."""
    parts = []
    for name in ("multibeam", "camera"):
        reached = ", ".join(f"{level} % never" if t is None else f"{level} % at {t:.0f} s"
                            for level, t in curve["time_to_s"][name].items())
        parts.append(f"{name} {reached}")
    return "- Coverage against time (`coverage_vs_time.png`): " + "; ".join(parts) + "."


def fig_coverage_vs_time(result: MissionResult, curve: dict) -> Figure:
    """Multibeam and camera coverage of the true target against mission time (`curve`, the
    report's `coverage_vs_time`), over the phases of the dive."""
    fig = Figure(figsize=(8, 4))
    ax = fig.add_subplot(1, 1, 1)
    for phase in result.phases:
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
    names = np.array([result.plan.legs[leg].phase for leg in result.leg_at])
    state = VehicleState(result.state)
    for name in dict.fromkeys(names):
        mask = names == name
        colour = PHASE_COLOURS.get(name, "k")
        t = np.where(mask, result.times, np.nan)
        ax.plot(t, np.where(mask, result.distance, np.nan), color=colour, lw=0.9,
                label=f"{name}: distance to the target")
        ax.plot(t, np.where(mask, result.clearance, np.nan), color=colour, lw=0.6, ls=":")
        top.plot(np.where(mask, state.x, np.nan), np.where(mask, state.y, np.nan),
                 color=colour, lw=0.8, label=name)
    band = near_distance(result) / 2.0
    if np.isfinite(band):  # a mission that only flies an exported file knows no Omega
        ax.axhline(band, color="k", ls="--", lw=0.8, label=f"Omega = {band:g} m")
    else:
        band = float(np.nanmax(result.distance)) / 3.0
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


def write_trajectory(result: MissionResult, filename) -> None:
    """`t`, the true pose (`signals.VehicleState`'s `x y z roll pitch yaw`) and the navigation's
    position (`est_x est_y est_z`), in the site's own horizontal coordinates, and the water's
    velocity at the true position (`current_x current_y current_z`, world frame: x east,
    y north, z up, m/s; zeros in still water)."""
    state, estimated = VehicleState(result.state), VehicleState(result.estimated)
    true_xyz = result.site.to_site(state.position)
    est_xyz = result.site.to_site(estimated.position)
    pose = VehicleState.get_fields()[:6]  # position and attitude
    current = (np.zeros((len(result.times), 3)) if result.water is None
               else Water(result.water).velocity)
    with open_replacing(filename, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["t", *pose, *(f"est_{name}" for name in pose[:3]),
                         "current_x", "current_y", "current_z"])
        for t, p, a, e, c in zip(result.times, true_xyz, state.attitude, est_xyz, current):
            writer.writerow([f"{t:.2f}", *(f"{v:.3f}" for v in p), *(f"{v:.5f}" for v in a),
                             *(f"{v:.3f}" for v in e), *(f"{v:.4f}" for v in c)])


def peak_rss_mb() -> float:
    """Peak resident memory of this process so far, MiB (`getrusage`: KiB on Linux)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def write_outputs(result: MissionResult, outdir, dpi: int = 110, setup_s: float | None = None,
                  finish=None, progress: RunProgress | None = None) -> dict:
    """Writes report.json, report.md, coverage.png, coverage_vs_time.png, distance.png, plan.png
    (coverage plans), trajectory.csv, diagram.dot and the data products (points.ply;
    reconstruction.ply and .png with Open3D, `reconstruction.products`) into `outdir`; returns
    the summary.

    `finish(outdir)` (the Meshcat recording, which reads the products) runs after the other
    files and before the report, so that `timing.outputs_s` counts it; `setup_s` is the
    caller's wall time before the simulation (see the module for the `timing` keys).
    `progress`: the run's display, whose `outputs` phase this runs, a step per file (or group
    of files) written."""
    start = time.perf_counter()
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    names = ["coverage.png", "distance.png", "coverage_vs_time.png",
             *(["plan.png"] if result.plan.coverage is not None else [])]
    files = [*names, "trajectory.csv", "diagram.dot", *(["mission.html"] if finish else [])]
    progress = progress if progress is not None else RunProgress.off()
    surface = len(SURFACE_STAGES) + 1 if result.spec.outputs.reconstruction else 0
    progress.start("outputs", total=len(files) + 3 + surface, note="summary")
    with progress.step("summary"):
        summary = summarise(result)
    products = time.perf_counter()
    summary["reconstruction"] = _rounded(write_products(
        result, out, dpi, surface=result.spec.outputs.reconstruction, progress=progress))
    reconstruction_s = time.perf_counter() - products
    makers = {"coverage.png": lambda: fig_coverage(result),
              "distance.png": lambda: fig_distance(result),
              "coverage_vs_time.png": lambda: fig_coverage_vs_time(
                  result, summary["coverage_vs_time"]),
              "plan.png": lambda: fig_path3d(result.plan.coverage)}
    for name in names:
        with progress.step(name), replacing(out / name) as temporary:
            makers[name]().savefig(temporary, dpi=dpi, bbox_inches="tight")
    with progress.step("trajectory.csv"):
        write_trajectory(result, out / "trajectory.csv")
    with progress.step("diagram.dot"):
        write_text(out / "diagram.dot", result.diagram_dot)
    if finish is not None:
        with progress.step("mission.html"):
            finish(out)
    with progress.step("report"):
        outputs_s = time.perf_counter() - start
        summary["timing"].update(_rounded(dict(
            setup_s=setup_s, outputs_s=outputs_s, reconstruction_s=reconstruction_s,
            total_s=(setup_s or 0.0) + result.wall_s + outputs_s, peak_rss_mb=peak_rss_mb())))
        write_json(out / "report.json", summary)
        write_text(out / "report.md",
                   report_markdown(summary, files) + "\n"
                   + products_markdown(summary["reconstruction"]))
    progress.finish(note=f"written to {out}")
    return summary
