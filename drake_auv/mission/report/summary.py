"""The report's numbers (`summarise`): coverage and viewing angles, the true and on-line map
distances to the target over the survey, per-phase statistics, the off-line plan's figures and
coverage against time (from the recorders' first-seen times)."""

from __future__ import annotations

import dataclasses

import numpy as np

from drake_auv.exploration.view_planner import exploration_summary
from drake_auv.geometry.distance import mesh_distance
from drake_auv.geometry.visibility import coverage_share
from drake_auv.mapping.mapper import map_memory
from drake_auv.mission.config import mission_to_dict
from drake_auv.mission.ocean_summary import ocean_summary
from drake_auv.mission.runner import VEHICLE_RADIUS, MissionResult
from drake_auv.signals import ReplanningStep, VehicleState


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
    names = np.array([result.plan.legs[leg].phase for leg in result.log.leg_at])
    scored = names == ("survey" if (names == "survey").any() else "follow")
    near = scored & (result.log.distance < near_distance(result))
    return near if near.any() else scored


def map_distance(result: MissionResult, samples: np.ndarray) -> np.ndarray:
    """Distance from `samples` (n, 3) to the on-line map's occupied voxels lying on the
    target (within 1.5 voxels of its true surface), m; inf without any."""
    from scipy.spatial import cKDTree

    voxels = result.mapping.online_map.map.occupied_points()
    if len(voxels) == 0 or len(samples) == 0:
        return np.full(len(samples), np.inf)
    on_target = (mesh_distance(result.site.target_mesh, voxels)
                 <= 1.5 * result.mapping.online_map.map.resolution)
    if not on_target.any():
        return np.full(len(samples), np.inf)
    return cKDTree(voxels[on_target]).query(samples)[0]


def phase_summary(result: MissionResult, mask: np.ndarray) -> dict:
    """Statistics of the samples `mask` of the dive."""
    t, xyz = result.log.times[mask], VehicleState(result.log.state[mask]).position
    nav_error = np.linalg.norm(VehicleState(result.log.estimated[mask]).position - xyz, axis=1)
    return dict(length_m=float(np.linalg.norm(np.diff(xyz, axis=0), axis=1).sum()),
                duration_s=float(t[-1] - t[0]) if len(t) else 0.0,
                distance_min_m=float(result.log.distance[mask].min()),
                clearance_min_m=float(result.log.clearance[mask].min()),
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
    end, areas = float(result.run.context.get_time()), result.coverage.areas
    out = dict(period_s=period_s, time_to_s={})
    for name in ("multibeam", "camera"):
        recorder = getattr(result.run.handles, f"{name}_coverage")
        first = recorder.first_seen(recorder.GetMyContextFromRoot(result.run.context))
        t, out[name] = coverage_curve(first, areas, end, period_s)
        out["t_s"] = t
        out["time_to_s"][name] = {f"{100 * level:g}": time_to_coverage(first, areas, level)
                                  for level in COVERAGE_LEVELS}
    return {k: v.tolist() if isinstance(v, np.ndarray) else v for k, v in out.items()}


def summarise(result: MissionResult) -> dict:
    """Everything the report shows; `timing` holds the wall-clock figures (they vary with the
    machine), the rest depends only on the mission file and its seed."""
    areas = result.coverage.areas
    scored = _scored_samples(result)
    d = result.log.distance[scored]
    map_d = map_distance(result, VehicleState(result.log.state[scored]).position)
    map_d = map_d[np.isfinite(map_d)]
    phases = []
    for phase in result.dive.phases:
        mask = np.isin(result.log.leg_at, phase.legs)
        entry = dict(name=phase.name, start_s=phase.start_s, end_s=phase.end_s,
                     legs=phase.legs, outcomes=[result.dive.outcomes[k] for k in phase.legs])
        if mask.any():
            entry.update(phase_summary(result, mask))
        phases.append(entry)
    cam_mean, cam_sd = angle_stats(result.coverage.camera_best, areas)
    mb_mean, mb_sd = angle_stats(result.coverage.multibeam_best, areas)
    min_clearance = float(result.log.clearance.min())
    summary = dict(
        mission=dict(name=result.spec.name, seed=result.spec.seed,
                     site=result.site.name, completed=result.dive.completed,
                     aborted="aborted" in result.dive.outcomes,
                     target_area_m2=float(areas.sum())),
        coverage=dict(multibeam=coverage_share(result.coverage.multibeam_best, areas),
                      camera=coverage_share(result.coverage.camera_best, areas),
                      multibeam_angle_mean_deg=mb_mean, multibeam_angle_sd_deg=mb_sd,
                      camera_angle_mean_deg=cam_mean, camera_angle_sd_deg=cam_sd),
        min_clearance_m=min_clearance,
        contact=bool(min_clearance <= VEHICLE_RADIUS),
        distance_to_target=dict(
            mean_m=float(d.mean()) if len(d) else None, sd_m=float(d.std()) if len(d) else None,
            min_m=float(result.log.distance.min()),
            map_mean_m=float(map_d.mean()) if len(map_d) else None,
            map_sd_m=float(map_d.std()) if len(map_d) else None,
            near_m=near_distance(result) if np.isfinite(near_distance(result)) else None,
            samples=int(scored.sum())),
        navigation_error_max_m=float(np.linalg.norm(
            VehicleState(result.log.estimated).position - VehicleState(result.log.state).position,
            axis=1).max()),
        phases=phases,
        faults={name: dataclasses.asdict(f) for name, f in result.spec.faults.active.items()},
        responses=result.dive.responses,
        plan=plan_summary(result),
        config=mission_to_dict(result.spec),
        coverage_vs_time=coverage_vs_time(result),
    )
    wall_s, sim_s = result.run.wall_s, result.log.duration_s
    timing = dict(wall_s=wall_s, sim_s=sim_s, simulation_s=wall_s,
                  real_time_factor=sim_s / max(wall_s, 1e-9))
    if len(result.mapping.replanning):
        wall = ReplanningStep(result.mapping.replanning).wall_time
        timing.update(replan_steps=len(wall), replan_median_ms=float(np.median(wall) * 1e3),
                      replan_p95_ms=float(np.percentile(wall, 95) * 1e3))
    summary["timing"] = timing
    summary["map"] = map_memory(result.mapping.online_map, result.mapping.scan_log)
    ocean = ocean_summary(result)
    if ocean is not None:
        summary["ocean"] = ocean
    if result.run.handles.explorer is not None:
        summary["exploration"] = exploration_summary(result.run.handles, result.run.context,
                                                     result.dive.outcomes)
    return rounded(summary)


def rounded(value, digits: int = 4):
    if isinstance(value, dict):
        return {k: rounded(v, digits) for k, v in value.items()}
    if isinstance(value, list):
        return [rounded(v, digits) for v in value]
    if isinstance(value, (float, np.floating)):
        return round(float(value), digits) if np.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    return value
